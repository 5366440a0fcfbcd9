// hovs rig: the variable-scale unit (rig/) in simulation. `align` runs the positioning loop on chosen mirrors
// from seeded disturbed starts (faults injectable) and writes the study; `switch` turns the turret from one
// mirror to another, aligns, focuses and loads the new mirror's calibration and mapping file from a rig folder.
#include <iostream>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "core/error.h"
#include "core/io.h"
#include "rig/rig_calibration.h"
#include "rig/rig_study.h"
#include "unwrap/remap_table.h"

namespace hovs::apps {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct CommonOptions {
  std::string machine = "scenes/turret.yaml";
  uint64_t seed = 1;
  int downscale = 0;
  int max_iterations = 30;
};

void AddCommon(CLI::App* app, CommonOptions* o) {
  app->add_option("-m,--machine", o->machine, "the machine file (rig/turret.h)")->capture_default_str();
  AddBounded(app, "--seed", &o->seed, "seed of the starts, seats and noise", 0, 9007199254740992.0);
  AddBounded(app, "--downscale", &o->downscale, "render at 1/N of the resolution (0: the machine file's)", 0, 16);
  AddBounded(app, "--max-iterations", &o->max_iterations, "positioning loop iterations at most", 1, 1000);
}

rig::TurretSpec LoadSpec(const CommonOptions& o) {
  rig::TurretSpec spec = rig::LoadTurretSpec(o.machine);
  if (o.downscale > 0) {
    HOVS_REQUIRE(spec.camera.width % o.downscale == 0 && spec.camera.height % o.downscale == 0, "--downscale",
                 o.downscale, " does not divide the image size ", spec.camera.width, "x", spec.camera.height);
    spec.downscale = o.downscale;
  }
  return spec;
}

struct AlignOptions {
  CommonOptions common;
  std::vector<std::string> mirrors;
  int starts = 20;
  double lateral_mm = 2, tilt_deg = 1.5, height_mm = 3;
  std::string fault, out = "results/rig-align";
  bool focus = false;
  rig::PidGains gains;
};
struct SwitchOptions {
  CommonOptions common;
  std::string from, to, rig_json, out = "results/rig-switch";
};
struct CalibrateOptions {
  CommonOptions common;
  int frames = 9;
  std::vector<std::string> mirrors;
  std::string out = "results/rig";
};

int RunAlign(const AlignOptions* a, const GlobalOptions* global) {
  const rig::TurretSpec spec = LoadSpec(a->common);
  rig::AlignStudyOptions o;
  for (const auto& id : a->mirrors) o.mirrors.push_back(spec.MirrorIndex(id));
  if (o.mirrors.empty())
    for (size_t k = 0; k < spec.mirrors.size(); ++k) o.mirrors.push_back(static_cast<int>(k));
  o.starts = a->starts;
  o.seed = a->common.seed;
  o.start = {a->lateral_mm * 1e-3, a->tilt_deg * kDeg, a->height_mm * 1e-3};
  o.align.max_iterations = a->common.max_iterations;
  o.focus = a->focus;
  o.align.lateral = o.align.height = o.align.tilt = a->gains;
  if (!a->fault.empty()) o.fault = rig::ParseFault(a->fault, "--fault");
  const auto runs = rig::RunAlignStudy(spec, o);
  const std::string summary = rig::WriteAlignReport(spec, o, runs, a->out);
  if (global->json)
    std::cout << ReadFile(std::filesystem::path(a->out) / "align.json");
  else if (!global->quiet)
    std::cout << summary;
  for (const auto& r : runs)
    if (!r.result.converged) {
      std::cerr << "hovs rig align: error: " << spec.mirrors[r.mirror].id << " (seed " << r.seed
                << "): " << r.result.failure << "; every step is in " << a->out << "/align.json\n";
      return 1;
    }
  return 0;
}

int RunCalibrate(const CalibrateOptions* c, const GlobalOptions* global) {
  const rig::TurretSpec spec = LoadSpec(c->common);
  rig::RigCalibrationOptions o;
  o.frames = c->frames;
  o.seed = c->common.seed;
  for (const auto& id : c->mirrors) o.mirrors.push_back(spec.MirrorIndex(id));
  const auto mirrors = rig::CalibrateRig(spec, o, c->out, Versions());
  if (!global->quiet)
    for (const auto& m : mirrors)
      std::cout << "hovs rig calibrate: " << m.mirror << ": " << m.boards << " boards, polynomial RMS " << m.rms_px
                << " px, calibrated at lateral " << m.pose.LateralM() * 1e3 << " mm, tilt " << m.pose.TiltRad() / kDeg
                << " deg, focus " << m.focus << " m\n";
  return 0;
}

int RunSwitch(const SwitchOptions* s, const GlobalOptions* global) {
  const rig::TurretSpec spec = LoadSpec(s->common);
  const int from = s->from.empty() ? 0 : spec.MirrorIndex(s->from), to = spec.MirrorIndex(s->to);
  std::optional<rig::RigFolder> folder;
  if (!s->rig_json.empty()) {  // bad files fail before the run
    folder = rig::LoadRigFolder(s->rig_json, spec);
    HOVS_REQUIRE(folder->downscale == spec.downscale, s->rig_json, "its calibrations are for images at 1/",
                 folder->downscale, " of the resolution but the switch renders at 1/", spec.downscale,
                 " (give --downscale ", folder->downscale, ")");
  }
  rig::AlignOptions ao;
  ao.max_iterations = s->common.max_iterations;
  const rig::SwitchResult r = rig::SimulateSwitch(spec, from, to, s->common.seed, ao, {});
  nlohmann::json j = rig::SwitchJson(spec, r);
  j["tool"] = "hovs rig switch";
  j["machine"] = spec.source;
  j["versions"] = Versions();
  if (folder && r.align.converged) {
    const auto it = folder->mirrors.find(spec.mirrors[to].id);
    HOVS_REQUIRE(it != folder->mirrors.end(), s->rig_json, "has no entry for mirror '", spec.mirrors[to].id, "'");
    const AnyModel model = AnyModel::Polynomial(it->second.model, it->second.calibration.string());
    const unwrap::RemapTable table = unwrap::LoadRemapTable(it->second.map);
    j["loaded"] = {{"calibration", it->second.calibration.string()},
                   {"model", model.KindName()},
                   {"map", it->second.map.string()},
                   {"map_views", table.views.size()}};
    // Does the stored calibration hold where the switch left the mirror? A fresh board, reprojected.
    const rig::FreshBoardCheck check =
        rig::CheckOnFreshBoard(spec, to, *r.align.final_truth, r.focus->focus, model, s->common.seed + 1000003u);
    j["fresh_board"] = {{"rms_px", check.rms_px}, {"corners", check.corners}, {"detection", check.status}};
  }
  StagedDirectory stage(s->out, "rig switch", {spec.source});
  WriteFileAtomic(stage.staging() / "switch.json", j.dump(1) + "\n");
  stage.Commit();
  const auto& t = r.align.final_truth;
  if (!global->quiet)
    std::cout << "hovs rig switch: " << spec.mirrors[from].id << " -> " << spec.mirrors[to].id << ": move "
              << r.move_seconds << " s, " << r.align.steps.size() << " loop iterations, truth lateral "
              << t->LateralM() * 1e3 << " mm, tilt " << t->TiltRad() / kDeg << " deg, height " << t->offset.z() * 1e3
              << " mm; focus " << (r.focus ? r.focus->focus : 0.0) << " m"
              << (r.focus ? rig::FocusAgainstPrediction(spec, to, r.focus->focus) : "") << "; " << r.machine_seconds
              << " s machine time\n";
  if (!r.align.converged) {
    std::cerr << "hovs rig switch: error: " << r.align.failure << "; every step is in " << s->out << "/switch.json\n";
    return 1;
  }
  return 0;
}

}  // namespace

Runner SetupRig(CLI::App* sub, const GlobalOptions* global) {
  sub->require_subcommand(1, 1);
  auto a = std::make_shared<AlignOptions>();
  auto s = std::make_shared<SwitchOptions>();
  auto c = std::make_shared<CalibrateOptions>();
  CLI::App* align = sub->add_subcommand("align", "Align mirrors from seeded disturbed starts; a study per mirror");
  AddCommon(align, &a->common);
  align->add_option("--mirror", a->mirrors, "mirror id (repeatable; default: every mirror)");
  AddBounded(align, "--starts", &a->starts, "seeded starts per mirror", 1, 1000);
  AddBounded(align, "--lateral-mm", &a->lateral_mm, "start: lateral offset (mm)", 0, 4);
  AddBounded(align, "--tilt-deg", &a->tilt_deg, "start: tilt (deg)", 0, 2.5);
  AddBounded(align, "--height-mm", &a->height_mm, "start: height error (mm)", 0, 10);
  align->add_option("--fault", a->fault, "inject AXIS:stuck, AXIS:lost=F or label:covered");
  align->add_flag("--focus", a->focus, "focus the lens after each alignment");
  AddBounded(align, "--kp", &a->gains.kp, "PID proportional gain (every axis)", 0, 2);
  AddBounded(align, "--ki", &a->gains.ki, "PID integral gain", 0, 1);
  AddBounded(align, "--kd", &a->gains.kd, "PID derivative gain", 0, 1);
  align->add_option("-o,--out", a->out, "report folder (replaced atomically)")->capture_default_str();
  CLI::App* sw = sub->add_subcommand("switch", "Switch to another mirror: turret, rod, alignment, focus, calibration");
  AddCommon(sw, &s->common);
  sw->add_option("--from", s->from, "the mirror over the camera at the start (default: the first)");
  sw->add_option("--to", s->to, "the mirror to switch to")->required();
  sw->add_option("--rig", s->rig_json, "rig.json: each mirror's calibration and mapping file, loaded after the switch");
  sw->add_option("-o,--out", s->out, "report folder (replaced atomically)")->capture_default_str();
  CLI::App* cal = sub->add_subcommand(
      "calibrate", "A rig folder: every mirror aligned, focused, calibrated on rendered boards, with its mapping file");
  AddCommon(cal, &c->common);
  AddBounded(cal, "--frames", &c->frames, "calibration boards per mirror", 3, 100);
  cal->add_option("--mirror", c->mirrors, "mirror id (repeatable; default: every mirror)");
  cal->add_option("-o,--out", c->out, "rig folder (replaced atomically)")->capture_default_str();

  return [=]() {
    if (align->parsed()) return RunAlign(a.get(), global);
    if (cal->parsed()) return RunCalibrate(c.get(), global);
    return RunSwitch(s.get(), global);
  };
}

}  // namespace hovs::apps
