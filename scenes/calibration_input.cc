#include "scenes/calibration_input.h"

#include <random>

#include "core/error.h"
#include "core/json.h"
#include "core/manifest.h"
#include "scenes/ground_truth.h"
#include "scenes/scene_config.h"

namespace hovs::scenes {
namespace {

// The manifest's first board when it is a checkerboard; else the user's (--board), which must then be given.
calib::CheckerboardDetectOptions BoardOf(const nlohmann::json& m, const std::filesystem::path& manifest,
                                         const DatasetCalibrationOptions& options) {
  calib::CheckerboardDetectOptions dopt = options.detect;
  if (m.contains("boards") && !m["boards"].empty() && JsonText(m["boards"][0], "type") == "charuco") {
    const auto& b = m["boards"][0];
    calib::CharucoSpec c;
    try {
      c.squares_x = b.at("squares").at(0), c.squares_y = b.at("squares").at(1);
      c.square = b.at("square"), c.marker = b.at("marker_length"), c.dictionary = b.at("dictionary");
    } catch (const nlohmann::json::exception& e) {
      throw Error(manifest.string() + " (boards[0])",
                  std::string("a charuco board needs squares, square, marker_length and dictionary: ") + e.what());
    }
    c.Check(manifest.string() + " (boards[0])");
    dopt.charuco = c;
    return dopt;
  }
  if (m.contains("boards") && !m["boards"].empty() && JsonText(m["boards"][0], "type") == "checker") {
    const auto& b = m["boards"][0];
    try {
      dopt.board.cols = b.at("inner_corners").at(0), dopt.board.rows = b.at("inner_corners").at(1);
      dopt.board.square = b.at("square");
    } catch (const nlohmann::json::exception& e) {
      throw Error(manifest.string() + " (boards[0])",
                  std::string("a checker board needs inner_corners and square: ") + e.what());
    }
    dopt.board.Check(manifest.string() + " (boards[0])");
  } else {
    HOVS_REQUIRE(dopt.board.square > 0 && !options.truth_corners, manifest.string(),
                 "the manifest describes no checkerboard; give --board");
  }
  return dopt;
}

}  // namespace

DatasetCalibrationInput LoadDatasetCalibrationInput(const std::filesystem::path& manifest,
                                                    const DatasetCalibrationOptions& options) {
  const auto m = LoadDatasetManifest(manifest);
  DatasetCalibrationInput out;
  calib::CalibrationInput& in = out.input;
  const auto dir = manifest.parent_path();
  int unit_index = -1;
  for (size_t u = 0; u < m["units"].size(); ++u)
    if (options.unit.empty() ? u == 0 : m["units"][u]["name"] == options.unit) unit_index = static_cast<int>(u);
  HOVS_REQUIRE(unit_index >= 0, manifest.string(), "no unit '", options.unit, "' in the manifest");
  const auto& uj = m["units"][unit_index];
  if (uj.contains("mirror")) {
    out.unit = UnitFromJson(uj, manifest.string() + " (units)");
    in.truth = out.unit->rig;
    in.width = out.unit->rig.camera.width, in.height = out.unit->rig.camera.height;
  }
  const calib::CheckerboardDetectOptions dopt = BoardOf(m, manifest, options);
  const double noise = options.corner_noise_px;
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> N(0, noise > 0 ? noise : 1);
  for (const auto& fr : m["frames"])
    for (const auto& v : fr["views"]) {
      if (v["unit"] != uj["name"]) continue;
      HOVS_REQUIRE(!options.truth_corners || v.contains("ground_truth"), manifest.string(),
                   "--truth-corners needs ground truth, and frame ", JsonText(v, "image"), " has none");
      if (!options.truth_corners) {
        std::vector<Vec2d> gt;
        if (v.contains("ground_truth"))
          for (const CornerTruth& c : VisibleSidecarCorners(dir / v["ground_truth"]["sidecar"].get<std::string>()))
            gt.push_back(c.pixel);
        calib::DetectInto(dir / v["image"].get<std::string>(), v["image"], dopt,
                          v.contains("ground_truth") ? &gt : nullptr, &in);
        continue;
      }
      calib::BoardObservation o;
      o.image = v["image"];
      for (const CornerTruth& c : VisibleSidecarCorners(dir / v["ground_truth"]["sidecar"].get<std::string>())) {
        o.board_points.emplace_back(c.board_xy.x(), c.board_xy.y(), 0.0);
        Vec2d px = c.pixel;
        if (noise > 0) px += Vec2d(N(rng), N(rng));
        o.pixels.push_back(px);
      }
      in.observations.push_back(o);
    }
  in.description = {{"dataset", manifest.string()}, {"unit", uj["name"]}};
  if (options.truth_corners)
    in.description.update({{"corners", "ground truth"}, {"corner_noise_px", noise}, {"seed", options.seed}});
  else if (dopt.charuco)
    in.description.update({{"corners", "hovs ChArUco detector"},
                           {"board",
                            {{"charuco", {dopt.charuco->squares_x, dopt.charuco->squares_y}},
                             {"square", dopt.charuco->square},
                             {"marker", dopt.charuco->marker},
                             {"dictionary", dopt.charuco->dictionary}}}});
  else
    in.description.update(
        {{"corners", "hovs checkerboard detector"}, {"board", {dopt.board.cols, dopt.board.rows, dopt.board.square}}});
  return out;
}

raytrace::CatadioptricUnit AlignedDesign(raytrace::CatadioptricUnit unit) {
  unit.rig.cam_from_mirror = MisalignedCamFromMirror(unit.rig.mirror, Vec3d::Zero(), Vec3d::Zero(), 0);
  return unit;
}

}  // namespace hovs::scenes
