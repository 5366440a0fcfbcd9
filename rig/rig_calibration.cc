#include "rig/rig_calibration.h"

#include <algorithm>
#include <cmath>
#include <unistd.h>

#include <sstream>

#include "calib/board_pose.h"
#include "core/error.h"
#include "core/io.h"
#include "scenes/calibration_input.h"
#include "scenes/dataset.h"
#include "scenes/scene_config.h"
#include "unwrap/layout.h"
#include "unwrap/remap_table.h"

namespace hovs::rig {
namespace fs = std::filesystem;

void RigCalibrationOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(frames >= 3 && frames <= 100, where, "frames must be 3..100");
}

namespace {

// A simulated unit on mirror k with the machine's seats, aligned and focused: its true pose and focus.
struct Prepared {
  MirrorPose pose;
  double focus = 0;
};

Prepared AlignAndFocus(const TurretSpec& spec, int k, uint64_t seed) {
  const auto seats = DrawSeats(spec, seed * 31u + 17u);
  SimulatedUnit unit(spec, k, spec.NominalAxes(k, spec.mirrors[k].PlateHeight()), seats, seed);
  const AlignResult a = Align(unit, spec, {});
  HOVS_REQUIRE(a.converged, "rig calibrate (mirror " + spec.mirrors[k].id + ")", a.failure);
  const FocusResult f = FocusLens(unit, spec, {});
  return {*unit.Truth(), f.focus};
}

}  // namespace

std::vector<MirrorCalibration> CalibrateRig(const TurretSpec& spec, const RigCalibrationOptions& o, const fs::path& out,
                                            const std::map<std::string, std::string>& versions) {
  o.Check("rig calibrate");
  for (size_t k = 0; k < spec.mirrors.size(); ++k)
    if (o.mirrors.empty() || std::find(o.mirrors.begin(), o.mirrors.end(), static_cast<int>(k)) != o.mirrors.end())
      RequireLabelPrecision(spec, static_cast<int>(k), {}, spec.source);
  StagedDirectory stage(out, "rig calibrate", {spec.source});
  const fs::path& dir = stage.staging();
  std::vector<MirrorCalibration> result;
  nlohmann::json rig = {{"format", "hovs-rig"},
                        {"version", kRigFolderVersion},
                        {"machine",
                         {{"source", spec.source},
                          {"name", spec.name},
                          {"geometry_checksum", TextChecksum(MachineGeometryJson(spec).dump())}}},
                        {"seed", o.seed},
                        {"downscale", spec.downscale},
                        {"mirrors", nlohmann::json::object()}};
  for (size_t k = 0; k < spec.mirrors.size(); ++k) {
    if (!o.mirrors.empty() && std::find(o.mirrors.begin(), o.mirrors.end(), static_cast<int>(k)) == o.mirrors.end())
      continue;
    const std::string id = spec.mirrors[k].id;
    const Prepared p = AlignAndFocus(spec, static_cast<int>(k), o.seed);
    scenes::SceneConfig cfg = TurretSceneConfig(spec, static_cast<int>(k), p.pose, p.focus, o.seed);
    cfg.render.samples = spec.board_samples;
    scenes::DatasetOptions d = scenes::DatasetOptions::ForKind("mono_calibration");
    d.count = o.frames;
    d.seed = o.seed;
    scenes::WriteCalibrationDataset(cfg, d, dir / id / "dataset", versions);
    const scenes::DatasetCalibrationInput in =
        scenes::LoadDatasetCalibrationInput(dir / id / "dataset" / "dataset.json", {});
    calib::MonoCalibrationOptions mo;
    mo.uncertainty = false;
    const calib::MonoCalibration c = calib::CalibrateMono(in.input, mo);
    nlohmann::json record = calib::MonoCalibrationJson(in.input, mo, c);
    record["tool"] = "hovs rig calibrate";
    record["versions"] = versions;
    fs::create_directories(dir / id / "calibration");
    calib::WriteMonoCalibrationReport(dir / id / "calibration", in.input, c, record);
    const AnyModel model = AnyModel::Polynomial(c.polynomial.model);
    const unwrap::RemapTable table = unwrap::BuildRemapTable(model, unwrap::ResolveLayout(o.layout, &model), {});
    unwrap::SaveRemapTable(dir / id / "views.hmap", table);
    const std::string calibration = id + "/calibration/calibration.json", map = id + "/views.hmap";
    const HyperboloidMirror<double>& mirror = spec.mirrors[k].mirror;
    rig["mirrors"][id] = {{"calibration", calibration},
                          {"calibration_checksum", FileChecksum(dir / calibration)},
                          {"map", map},
                          {"map_checksum", FileChecksum(dir / map)},
                          {"mirror", {{"a", mirror.a}, {"b", mirror.b}, {"rim_diameter", mirror.rim_diameter}}},
                          {"pose",
                           {{"lateral_mm", p.pose.LateralM() * 1e3},
                            {"tilt_deg", p.pose.TiltRad() * 180 / M_PI},
                            {"height_mm", p.pose.offset.z() * 1e3}}},
                          {"focus_m", p.focus},
                          {"rms_px", c.polynomial.rms}};
    result.push_back({id, p.pose, p.focus, c.polynomial.rms, static_cast<int>(in.input.observations.size())});
  }
  rig["versions"] = versions;
  WriteFileAtomic(dir / "rig.json", rig.dump(2) + "\n");
  stage.Commit();
  return result;
}

FreshBoardCheck CheckOnFreshBoard(const TurretSpec& spec, int k, const MirrorPose& pose, double focus,
                                  const AnyModel& model, uint64_t seed) {
  const fs::path tmp = fs::temp_directory_path() / ("hovs-fresh-board-" + std::to_string(::getpid()) + "-" +
                                                    std::to_string(seed) + "-" + std::to_string(k));
  fs::remove_all(tmp);
  struct Cleanup {
    fs::path p;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(p, ec);
    }
  } cleanup{tmp};
  scenes::SceneConfig cfg = TurretSceneConfig(spec, k, pose, focus, seed);
  cfg.render.samples = spec.board_samples;
  scenes::DatasetOptions d = scenes::DatasetOptions::ForKind("mono_calibration");
  d.count = 1;
  d.seed = seed;
  scenes::WriteCalibrationDataset(cfg, d, tmp, {});
  const scenes::DatasetCalibrationInput in = scenes::LoadDatasetCalibrationInput(tmp / "dataset.json", {});
  FreshBoardCheck r;
  if (!in.input.detection.empty()) r.status = in.input.detection.front().status;
  HOVS_REQUIRE(!in.input.observations.empty(), "fresh board (mirror " + spec.mirrors.at(k).id + ")",
               "no board found: ", r.status);
  const calib::BoardObservation& ob = in.input.observations.front();
  Rigid3d mirror_from_board;
  HOVS_REQUIRE(calib::FitBoardPose(model, ob.board_points, ob.pixels, &mirror_from_board, &r.rms_px),
               "fresh board (mirror " + spec.mirrors.at(k).id + ")", "the stored model fits no board pose");
  r.corners = static_cast<int>(ob.pixels.size());
  return r;
}

}  // namespace hovs::rig
