// hovs calibrate: monocular calibration from a corner table (e.g. shared/data/vmr) or from a dataset manifest.
// With a synthetic manifest, the ground-truth corners are used (optionally with seeded noise) and the result is
// compared with the exact rig: this checks the solver until hovs' own detector lands (issue 4).
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>

#include "apps/commands.h"
#include "calib/ocam_io.h"
#include "calib/omnidir_reference.h"
#include "calib/polynomial_calibration.h"
#include "core/error.h"
#include "core/io.h"
#include "design/study.h"
#include "results/html.h"
#include "results/plot.h"
#include "scenes/ground_truth.h"

namespace hovs::apps {
namespace {

std::string F(const char* fmt, double v) {
  char b[64];
  std::snprintf(b, sizeof b, fmt, v);
  return b;
}

struct Input {
  std::vector<calib::BoardObservation> obs;
  int width = 0, height = 0;
  std::optional<raytrace::CatadioptricUnit> truth;  // synthetic datasets only
  nlohmann::json description;
};

Input FromDataset(const std::filesystem::path& manifest, const std::string& unit_name, double noise, uint64_t seed) {
  const auto m = nlohmann::json::parse(ReadFile(manifest), nullptr, false);
  HOVS_REQUIRE(!m.is_discarded() && m.value("format", "") == "hovs-dataset", manifest.string(),
               "not a hovs dataset manifest");
  Input in;
  const auto dir = manifest.parent_path();
  int unit_index = -1;
  for (size_t u = 0; u < m["units"].size(); ++u)
    if (unit_name.empty() ? u == 0 : m["units"][u]["name"] == unit_name) unit_index = static_cast<int>(u);
  HOVS_REQUIRE(unit_index >= 0, manifest.string(), "no unit '", unit_name, "' in the manifest");
  const auto& uj = m["units"][unit_index];
  in.truth = scenes::UnitFromJson(uj, manifest.string() + " (units)");
  in.width = in.truth->rig.camera.width, in.height = in.truth->rig.camera.height;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> N(0, noise > 0 ? noise : 1);
  for (const auto& fr : m["frames"])
    for (const auto& v : fr["views"]) {
      if (v["unit"] != uj["name"]) continue;
      HOVS_REQUIRE(v.contains("ground_truth"), manifest.string(),
                   "frame without ground truth: corner detection is not in hovs yet (issue 4); use --corners");
      const auto side = nlohmann::json::parse(ReadFile(dir / v["ground_truth"]["sidecar"].get<std::string>()));
      calib::BoardObservation o;
      o.image = v["image"];
      for (const auto& c : side["boards"][0]["corners"]) {
        if (c["status"] != "visible") continue;
        o.board_points.emplace_back(c["board"][0].get<double>(), c["board"][1].get<double>(), 0.0);
        Vec2d px(c["pixel"][0].get<double>(), c["pixel"][1].get<double>());
        if (noise > 0) px += Vec2d(N(rng), N(rng));
        o.pixels.push_back(px);
      }
      in.obs.push_back(o);
    }
  in.description = {{"dataset", manifest.string()}, {"unit", uj["name"]}, {"corners", "ground truth"},
                    {"corner_noise_px", noise}, {"seed", seed}};
  return in;
}

nlohmann::json PolyJson(const calib::PolynomialCalibration& r, const std::vector<calib::BoardObservation>& obs) {
  const auto& m = r.model;
  nlohmann::json j = {{"model", "polynomial"},
                      {"cx", m.cx}, {"cy", m.cy}, {"c", m.c}, {"d", m.d}, {"e", m.e},
                      {"poly", m.poly}, {"inv_poly", m.inv_poly}, {"rho_range", {m.rho_min, m.rho_max}},
                      {"width", m.width}, {"height", m.height},
                      {"rms_px", r.rms}, {"mean_px", r.mean}, {"initial_rms_px", r.initial_rms},
                      {"converged", r.converged}, {"solver", r.solver_report}, {"stddev", r.stddev}};
  nlohmann::json per = nlohmann::json::array();
  for (size_t i = 0; i < obs.size(); ++i)
    per.push_back({{"image", obs[i].image}, {"corners", obs[i].pixels.size()}, {"rms_px", r.per_image_rms[i]},
                   {"mean_px", r.per_image_mean[i]}, {"above_5px", r.per_image_mean[i] > 5.0}});
  j["per_image"] = per;
  return j;
}

}  // namespace

Runner SetupCalibrate(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string corners, size, dataset, unit, out = "results/calibration", loss = "none";
    std::vector<int> degrees = {2, 3, 4, 5, 6};
    int degree = 4;
    double loss_scale = 1.0, noise = 0.0;
    uint64_t seed = 1;
    bool omnidir = false;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("--corners", o->corners, "corner table: image,corner,board_x_mm,board_y_mm,u_px,v_px");
  sub->add_option("--size", o->size, "image size WxH (with --corners)");
  sub->add_option("--dataset", o->dataset, "dataset manifest (dataset.json) with ground-truth corners");
  sub->add_option("--unit", o->unit, "unit name in the manifest (default: the first)");
  sub->add_option("--corner-noise", o->noise, "Gaussian noise added to ground-truth corners, px")->capture_default_str();
  sub->add_option("--seed", o->seed, "seed of the corner noise")->capture_default_str();
  sub->add_option("--degree", o->degree, "polynomial degree of the reported model")->capture_default_str();
  sub->add_option("--loss", o->loss, "none | huber | cauchy")->capture_default_str();
  sub->add_option("--loss-scale", o->loss_scale, "robust loss scale, px")->capture_default_str();
  sub->add_flag("--compare-omnidir", o->omnidir, "also run OpenCV omnidir on the same corners");
  sub->add_option("-o,--out", o->out, "report folder (replaced atomically)")->capture_default_str();
  return [o, global]() {
    HOVS_REQUIRE(o->corners.empty() != o->dataset.empty(), "hovs calibrate", "give either --corners or --dataset");
    Input in;
    if (!o->corners.empty()) {
      int w = 0, h = 0;
      char x = 0;
      HOVS_REQUIRE(std::sscanf(o->size.c_str(), "%d%c%d", &w, &x, &h) == 3 && x == 'x' && w > 0 && h > 0, "--size",
                   "expected WxH, e.g. 1024x768 (got '", o->size, "')");
      in.obs = calib::LoadCornerCsv(o->corners);
      in.width = w, in.height = h;
      in.description = {{"corners", o->corners}, {"size", {w, h}}};
      for (const auto& ob : in.obs)
        for (const auto& p : ob.pixels)
          HOVS_REQUIRE(p.x() >= -0.5 && p.y() >= -0.5 && p.x() <= w - 0.5 && p.y() <= h - 0.5, o->corners,
                       "corner (", p.x(), ", ", p.y(), ") of ", ob.image, " lies outside the ", w, "x", h, " image");
    } else {
      in = FromDataset(o->dataset, o->unit, o->noise, o->seed);
    }
    calib::PolynomialCalibrationOptions po;
    po.loss = o->loss, po.loss_scale = o->loss_scale;
    // Order selection table (the article's Tables 1-2), then the reported degree.
    nlohmann::json orders = nlohmann::json::array();
    std::optional<calib::PolynomialCalibration> chosen;
    for (int d : o->degrees) {
      po.degree = d;
      const auto r = calib::CalibratePolynomial(in.obs, in.width, in.height, po);
      nlohmann::json row = {{"degree", d}, {"rms_px", r.rms}, {"mean_px", r.mean}, {"converged", r.converged},
                            {"per_image_mean_px", r.per_image_mean}};
      orders.push_back(row);
      if (d == o->degree) chosen = r;
    }
    if (!chosen) {
      po.degree = o->degree;
      chosen = calib::CalibratePolynomial(in.obs, in.width, in.height, po);
    }
    const calib::UnifiedCalibration uni = calib::CalibrateUnified(in.obs, in.width, in.height, *chosen, o->loss, o->loss_scale);
    nlohmann::json j;
    j["tool"] = "hovs calibrate";
    j["versions"] = design::DesignVersions();
    j["input"] = in.description;
    j["input"]["images"] = in.obs.size();
    j["polynomial"] = PolyJson(*chosen, in.obs);
    j["unified"] = {{"model", "unified_radtan"}, {"xi", uni.model.xi}, {"fx", uni.model.fx}, {"fy", uni.model.fy},
                    {"cx", uni.model.cx}, {"cy", uni.model.cy},
                    {"distortion", {uni.model.distortion.k1, uni.model.distortion.k2, uni.model.distortion.p1, uni.model.distortion.p2}},
                    {"rms_px", uni.rms}, {"mean_px", uni.mean}, {"converged", uni.converged}, {"solver", uni.solver_report}};
    j["order_selection"] = orders;
    if (o->omnidir) {
      const auto cv = calib::RunOpenCvOmnidir(in.obs, in.width, in.height);
      j["opencv_omnidir"] = cv.ok ? nlohmann::json{{"rms_px", cv.rms}, {"opencv_reported_rms", cv.opencv_rms},
                                                   {"images_used", cv.images_used}, {"xi", cv.xi}, {"fx", cv.fx},
                                                   {"fy", cv.fy}, {"cx", cv.cx}, {"cy", cv.cy}}
                                  : nlohmann::json{{"error", cv.error}};
    }
    if (in.truth) {
      // Mean angle between calibrated and true rays over the calibrated annulus.
      const auto& rig = in.truth->rig;
      double sum = 0, worst = 0;
      int n = 0;
      for (int v = 0; v < in.height; v += 25)
        for (int u = 0; u < in.width; u += 25) {
          const Vec2d uv(u, v);
          const double rho = chosen->model.SensorFromImg(uv).norm();
          if (!rig.SeesMirror(uv) || rho < chosen->model.rho_min || rho > chosen->model.rho_max) continue;
          Vec3d a, b;
          if (!rig.CamFromImg(uv, &a) || !chosen->model.CamFromImg(uv, &b)) continue;
          const double ang = std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / M_PI;
          sum += ang, worst = std::max(worst, ang), ++n;
        }
      j["ground_truth"] = {{"mean_ray_angle_deg", n ? sum / n : 0.0}, {"max_ray_angle_deg", worst}, {"pixels", n},
                           {"true_centre", {rig.camera.cx, rig.camera.cy}}};
    }
    StagedDirectory stage(o->out);
    WriteFileAtomic(stage.staging() / "calibration.json", j.dump(2) + "\n");
    WriteFileAtomic(stage.staging() / "calib_results.txt", calib::FormatOcamCalibResults(chosen->model));
    std::string summary = "hovs calibrate: " + std::to_string(in.obs.size()) + " images\n";
    summary += "  polynomial (degree " + std::to_string(chosen->model.Degree()) + "): RMS " + F("%.4f", chosen->rms) +
               " px, mean " + F("%.4f", chosen->mean) + " px (linear start " + F("%.3f", chosen->initial_rms) + " px)\n";
    summary += "  unified + radtan:         RMS " + F("%.4f", uni.rms) + " px\n";
    if (j.contains("opencv_omnidir") && j["opencv_omnidir"].contains("rms_px"))
      summary += "  OpenCV omnidir (same corners): RMS " + F("%.4f", j["opencv_omnidir"]["rms_px"].get<double>()) + " px\n";
    if (j.contains("ground_truth"))
      summary += "  vs ground truth: mean ray angle " + F("%.5f", j["ground_truth"]["mean_ray_angle_deg"].get<double>()) + " deg\n";
    for (size_t i = 0; i < in.obs.size(); ++i)
      if (chosen->per_image_mean[i] > 5.0) summary += "  POOR: " + in.obs[i].image + " mean error above 5 px\n";
    WriteFileAtomic(stage.staging() / "summary.txt", summary);
    results::HtmlPage page("hovs calibration");
    page.Preformatted(summary);
    page.Heading("Per-image mean reprojection error by polynomial degree (px)");
    std::vector<std::string> header = {"image"};
    for (const auto& r : orders) header.push_back("N = " + std::to_string(r["degree"].get<int>()));
    std::vector<std::vector<std::string>> rows;
    for (size_t i = 0; i < in.obs.size(); ++i) {
      std::vector<std::string> row = {in.obs[i].image};
      for (const auto& r : orders) row.push_back(F("%.4f", r["per_image_mean_px"][i].get<double>()));
      rows.push_back(row);
    }
    std::vector<std::string> all = {"all (RMS)"};
    for (const auto& r : orders) all.push_back(F("%.4f", r["rms_px"].get<double>()));
    rows.push_back(all);
    page.Table(header, rows);
    page.Heading("Result");
    page.Preformatted(j.dump(2));
    WriteFileAtomic(stage.staging() / "index.html", page.Render());
    stage.Commit();
    if (global->json) std::cout << j.dump(2) << "\n";
    else if (!global->quiet) std::cout << summary;
    return 0;
  };
}

}  // namespace hovs::apps
