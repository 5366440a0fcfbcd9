#include "hw/rig_live.h"

#include <chrono>
#include <cstdio>
#include <memory>

#include "core/error.h"
#include "core/statistics.h"

namespace hovs::hw {
namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

nlohmann::json Latency(const std::vector<double>& v) {
  if (v.empty()) return nlohmann::json();
  const SampleSummary s = Summarise(v);
  return {{"median_ms", s.median}, {"p95_ms", s.p95}, {"max_ms", s.max}, {"frames", s.count}};
}

nlohmann::json PoseJson(const rig::MirrorPose& p) {
  return {
      {"lateral_mm", p.LateralM() * 1e3}, {"tilt_deg", p.TiltRad() * 180 / M_PI}, {"height_mm", p.offset.z() * 1e3}};
}

}  // namespace

RigLiveRun RunRigLive(rig::SimulatedRigStream& stream, const rig::TurretSpec& spec,
                      const std::map<int, unwrap::RemapTable>& tables, const RigLiveOptions& o, std::atomic<bool>* stop,
                      const std::function<void(const std::vector<unwrap::Image8>&)>& display) {
  HOVS_REQUIRE(o.frames > 0, "rig live", "give a positive frame count");
  HOVS_REQUIRE(o.write_every == 0 || !o.out_dir.empty(), "rig live", "writing views needs an output folder");
  for (const auto& [frame, k] : o.switches)
    HOVS_REQUIRE(tables.count(k), "rig live", "a switch at frame ", frame, " goes to mirror '", spec.mirrors.at(k).id,
                 "', which has no mapping");
  std::map<int, std::unique_ptr<unwrap::Remapper>> remappers;
  for (const auto& [k, table] : tables) remappers[k] = std::make_unique<unwrap::Remapper>(table);
  RigLiveRun r;
  std::vector<unwrap::Image8> views;
  int current = -1, ready = 0;
  const auto t_start = Clock::now();
  for (int64_t i = 0; i < o.frames && !stop->load(); ++i) {
    for (const auto& [frame, k] : o.switches)
      if (frame == i) stream.RequestSwitch(k);
    const auto t0 = Clock::now();
    const rig::StreamedFrame f = stream.Next();
    const auto t1 = Clock::now();
    RigLiveFrame log;
    log.index = f.index, log.time = f.time, log.mirror = f.mirror, log.state = f.state, log.truth = f.truth;
    log.within_tolerance = o.tolerance.Holds(f.truth);
    if (!f.Ready()) {
      ++r.held;
      r.held_within_tolerance += log.within_tolerance;
      r.frames.push_back(log);
      continue;
    }
    r.ready_outside_tolerance += !log.within_tolerance;
    const auto it = tables.find(f.mirror);
    HOVS_REQUIRE(it != tables.end(), "rig live", "the unit is ready on mirror '", spec.mirrors.at(f.mirror).id,
                 "', which has no mapping");
    const unwrap::RemapTable& table = it->second;
    const rig::TurretImage& img = f.image.value();
    HOVS_REQUIRE(img.width == table.source_width && img.height == table.source_height, "rig live", "the frames are ",
                 img.width, " x ", img.height, " but the mapping of mirror '", spec.mirrors.at(f.mirror).id,
                 "' is for ", table.source_width, " x ", table.source_height);
    r.swaps += current >= 0 && current != f.mirror;
    current = f.mirror;
    remappers.at(f.mirror)->Run(
        {img.grey.data(), img.width, img.height, size_t(img.width), unwrap::PixelFormat::kGray8}, o.interpolation,
        &views);
    const auto t2 = Clock::now();
    if (o.write_every > 0 && ready % o.write_every == 0) {
      char stem[96];
      std::snprintf(stem, sizeof stem, "frame%06lld_%s", static_cast<long long>(f.index),
                    spec.mirrors.at(f.mirror).id.c_str());
      WriteLiveViews(o.out_dir, stem, table, views);
      log.written = true;
      ++r.live.written;
    }
    const auto t3 = Clock::now();
    if (display) display(views);
    const auto t4 = Clock::now();
    log.expanded = true;
    ++ready;
    r.live.wait_ms.push_back(Ms(t0, t1)), r.live.remap_ms.push_back(Ms(t1, t2));
    if (o.write_every > 0) r.live.write_ms.push_back(Ms(t2, t3));
    if (display) r.live.display_ms.push_back(Ms(t3, t4));
    r.live.total_ms.push_back(Ms(t1, t4));
    r.frames.push_back(log);
  }
  r.live.processed = ready;
  r.live.seconds = Ms(t_start, Clock::now()) / 1e3;
  return r;
}

nlohmann::json RigLiveJson(const rig::TurretSpec& spec, const RigLiveRun& r,
                           const std::vector<rig::SwitchRecord>& switches, const RigLiveOptions& o) {
  std::map<std::string, int> held;
  for (const auto& f : r.frames)
    if (!f.expanded) ++held[rig::UnitStateName(f.state)];
  nlohmann::json sw = nlohmann::json::array();
  for (const auto& s : switches) {
    nlohmann::json j = {{"from", spec.mirrors.at(s.from).id},
                        {"to", spec.mirrors.at(s.to).id},
                        {"frames", {s.first_frame, s.last_frame}},
                        {"machine_seconds", s.end_time - s.start_time},
                        {"converged", s.align.converged},
                        {"loop_iterations", s.align.steps.size()},
                        {"failure", s.failure}};
    if (s.align.final_truth) j["final_truth"] = PoseJson(*s.align.final_truth);
    if (s.focus) j["focus"] = {{"distance_m", s.focus->focus}, {"images", s.focus->images}};
    sw.push_back(j);
  }
  nlohmann::json frames = nlohmann::json::array();
  for (const auto& f : r.frames) {
    nlohmann::json j = {{"index", f.index},
                        {"time_s", f.time},
                        {"mirror", spec.mirrors.at(f.mirror).id},
                        {"state", rig::UnitStateName(f.state)},
                        {"expanded", f.expanded},
                        {"written", f.written},
                        {"within_tolerance", f.within_tolerance}};
    j["truth"] = PoseJson(f.truth);
    frames.push_back(j);
  }
  return {{"frames_streamed", r.frames.size()},
          {"frames_expanded", r.live.processed},
          {"frames_held", r.held},
          {"held_by_state", held},
          {"frames_written", r.live.written},
          {"ready_outside_tolerance", r.ready_outside_tolerance},
          {"held_within_tolerance", r.held_within_tolerance},
          {"mapping_swaps", r.swaps},
          {"tolerance",
           {{"lateral_mm", o.tolerance.lateral * 1e3},
            {"tilt_deg", o.tolerance.tilt * 180 / M_PI},
            {"height_mm", o.tolerance.height * 1e3}}},
          {"seconds", r.live.seconds},
          {"switches", sw},
          {"latency",
           {{"next_frame", Latency(r.live.wait_ms)},
            {"remap", Latency(r.live.remap_ms)},
            {"write", Latency(r.live.write_ms)},
            {"frame_to_output", Latency(r.live.total_ms)}}},
          {"frames", frames}};
}

}  // namespace hovs::hw
