// hovs position: visual positioning of the mirror over the camera (the rig's turret and height rod). From one
// image and the unit's design, the rim of the mirror image is found and the camera centre's offset from the
// design's second focus is estimated (calib/rim_positioning.h), with the adjustment that brings it back.
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "calib/rim_positioning.h"
#include "core/error.h"
#include "core/io.h"
#include "scenes/ground_truth.h"
#include "scenes/scene_config.h"

namespace hovs::apps {
namespace fs = std::filesystem;

Runner SetupPosition(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::string image, scene, unit, out = "results/position";
    calib::RimEdgeOptions edge;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("-i,--image", o->image, "an image of the unit (grey or RGB; a raw Bayer mosaic works as grey)")
      ->required();
  sub->add_option("--design", o->scene, "the unit's design: scene YAML or dataset.json (its misalignment is ignored)")
      ->required();
  sub->add_option("--unit", o->unit, "unit name (default: the first)");
  AddBounded(sub, "--rays", &o->edge.rays, "rim search rays", 16, 100000);
  AddBounded(sub, "--search", &o->edge.search_px, "rim search half width around the design's rim, px", 1, 2000, true);
  AddBounded(sub, "--min-step", &o->edge.min_step, "grey levels across the rim edge, at least", 0, 255, true);
  sub->add_option("-o,--out", o->out, "report folder (replaced atomically)")->capture_default_str();
  return [o, global]() {
    o->edge.Check("--rays/--search/--min-step");
    // The design: the unit's rig with the camera at the second focus, aligned.
    CatadioptricCamera<double> design;
    std::string unit_name;
    const fs::path spec(o->scene);
    RequireFile(spec, "design file");
    if (spec.extension() == ".json") {
      const auto m = LoadDatasetManifest(spec);
      const auto& units = m.at("units");
      size_t k = 0;
      if (!o->unit.empty()) {
        for (k = 0; k < units.size() && units[k]["name"] != o->unit; ++k) {}
        HOVS_REQUIRE(k < units.size(), "--unit " + o->unit, "no such unit in ", o->scene);
      }
      const auto u = scenes::UnitFromJson(units[k], o->scene + " (units)");
      design = u.rig, unit_name = u.name;
    } else {
      auto cfg = scenes::LoadSceneConfig(spec);
      if (!o->unit.empty()) scenes::SelectUnit(&cfg, o->unit);
      design = cfg.description.units[0].rig, unit_name = cfg.description.units[0].name;
    }
    design.cam_from_mirror = scenes::MisalignedCamFromMirror(design.mirror, Vec3d::Zero(), Vec3d::Zero(), 0);
    const auto img = LoadImage8(o->image);
    HOVS_REQUIRE(img.width == design.camera.width && img.height == design.camera.height, o->image, "the image is ",
                 img.width, "x", img.height, " but the design's camera is ", design.camera.width, "x",
                 design.camera.height);
    std::vector<uint8_t> grey(size_t(img.width) * img.height);
    for (size_t k = 0; k < grey.size(); ++k) {
      int s = 0;
      for (int c = 0; c < img.channels; ++c) s += img.data[k * img.channels + c];
      grey[k] = static_cast<uint8_t>(s / img.channels);
    }
    calib::RimEdge edge;
    const calib::MirrorPosition p =
        calib::LocateMirror(grey.data(), img.width, img.height, design, o->edge, &edge, o->image);
    const Vec3d mm = 1e3 * p.offset;
    nlohmann::json j = {
        {"tool", "hovs position"},
        {"versions", Versions()},
        {"image", o->image},
        {"design", o->scene},
        {"unit", unit_name},
        {"camera_offset_mm", {mm.x(), mm.y(), mm.z()}},
        {"note",
         "camera centre minus the design's second focus, mirror frame (z towards the mirror), "
         "the camera's orientation held at the design's"},
        {"equivalent_tilt_deg", {p.equivalent_tilt_rad.x() * 180 / M_PI, p.equivalent_tilt_rad.y() * 180 / M_PI}},
        {"rim",
         {{"centre_px", {p.rim_centre_px.x(), p.rim_centre_px.y()}},
          {"radius_px", p.rim_radius_px},
          {"design_centre_px", {p.nominal_rim_centre_px.x(), p.nominal_rim_centre_px.y()}},
          {"design_radius_px", p.nominal_rim_radius_px}}},
        {"edge_points", p.points},
        {"rays", edge.rays},
        {"rms_px", p.rms_px},
        {"converged", p.converged},
        {"rim_inliers", p.inliers},
        {"edge_points_hidden_by_mount", p.occluded},
        {"rim_inlier_fraction", p.inlier_fraction}};
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "hovs position: rim found on %d of %d rays (fit RMS %.3f px)\n"
                  "  camera centre off the design by (%.3f, %.3f) mm laterally and %.3f mm along the axis "
                  "(+ towards the mirror)\n"
                  "  adjust: move the camera by (%.3f, %.3f) mm and %s it by %.3f mm (height rod)\n"
                  "  (if the camera is on the axis but tilted instead: tilt (%.3f, %.3f) deg)\n",
                  p.points, edge.rays, p.rms_px, mm.x(), mm.y(), mm.z(), -mm.x(), -mm.y(),
                  mm.z() > 0 ? "lower" : "raise", std::abs(mm.z()), p.equivalent_tilt_rad.x() * 180 / M_PI,
                  p.equivalent_tilt_rad.y() * 180 / M_PI);
    // Figure: the image with the design's rim (blue), the fitted rim (green) and the edge points (red).
    cv::Mat fig(img.height, img.width, CV_8UC1, grey.data());
    cv::cvtColor(fig, fig, cv::COLOR_GRAY2BGR);
    const auto draw_rim = [&](const CatadioptricCamera<double>& rig, const cv::Scalar& colour) {
      std::vector<cv::Point> poly;
      for (int k = 0; k < 720; ++k) {
        const double a = 2 * M_PI * k / 720, R = rig.mirror.RimRadius();
        Vec2d uv;
        if (rig.camera.ImgFromCam(rig.cam_from_mirror * Vec3d(R * std::cos(a), R * std::sin(a), rig.mirror.RimZ()),
                                  &uv))
          poly.emplace_back(static_cast<int>(std::lround(uv.x())), static_cast<int>(std::lround(uv.y())));
      }
      cv::polylines(fig, poly, true, colour, std::max(1, img.width / 900), cv::LINE_AA);
    };
    draw_rim(design, cv::Scalar(255, 120, 0));
    draw_rim(calib::WithCameraOffset(design, p.offset), cv::Scalar(0, 200, 0));
    for (const Vec2d& e : edge.points)
      cv::circle(fig, cv::Point2d(e.x(), e.y()), std::max(1, img.width / 700), cv::Scalar(0, 0, 255), cv::FILLED);
    StagedDirectory stage(o->out, "position");
    WriteFileAtomic(stage.staging() / "position.json", j.dump(2) + "\n");
    WriteFileAtomic(stage.staging() / "summary.txt", buf);
    HOVS_REQUIRE(cv::imwrite((stage.staging() / "rim.png").string(), fig), o->out, "cannot write rim.png");
    stage.Commit();
    if (global->json)
      std::cout << j.dump(2) << "\n";
    else if (!global->quiet)
      std::cout << buf;
    return 0;
  };
}

}  // namespace hovs::apps
