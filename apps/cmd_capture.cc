// hovs capture: frames from one or two GigE Vision cameras (Aravis), a replayed folder, or Aravis' GigE Vision
// simulator serving a rendered dataset (--simulate), written as a hovs dataset (dataset.json without ground
// truth, per-frame metadata, stream statistics). Ctrl-C ends the capture with a valid manifest.
#include <atomic>
#include <csignal>
#include <cstdio>
#include <iostream>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "core/error.h"
#include "design/study.h"
#include "hw/capture.h"
#include "hw/fake_gige.h"

namespace hovs::apps {
namespace {
namespace fs = std::filesystem;

std::atomic<bool> g_stop{false};
extern "C" void OnSigint(int) { g_stop.store(true); }

// The images of one unit of a rendered dataset, as the simulator's frames (Mono8: grey; BayerRG8: the mosaic).
std::vector<hw::FakeFrame> SimulatorFrames(const nlohmann::json& m, const fs::path& manifest, const std::string& unit,
                                           const std::string& format) {
  std::vector<hw::FakeFrame> frames;
  for (const auto& fr : m.at("frames"))
    for (const auto& v : fr.at("views")) {
      if (v.at("unit") != unit) continue;
      const auto im = LoadImage8(manifest.parent_path() / v.at("image").get<std::string>());
      HOVS_REQUIRE(format == "Mono8" || im.channels == 1, manifest.string(), "BayerRG8 simulation needs mosaic images");
      hw::FakeFrame f;
      f.width = im.width, f.height = im.height;
      f.data.resize(size_t(im.width) * im.height);
      for (size_t k = 0; k < f.data.size(); ++k)
        f.data[k] = im.channels == 1 ? im.data[k]
                                     : static_cast<uint8_t>((299 * im.data[3 * k] + 587 * im.data[3 * k + 1] +
                                                             114 * im.data[3 * k + 2] + 500) / 1000);
      frames.push_back(std::move(f));
    }
  HOVS_REQUIRE(!frames.empty(), manifest.string(), "no images of unit '", unit, "'");
  return frames;
}

}  // namespace

Runner SetupCapture(CLI::App* sub, const GlobalOptions* global) {
  struct Options {
    std::vector<std::string> cameras, units, features;
    std::string replay, simulate, out = "results/capture", region, pixel_format = "Mono8", trigger = "free";
    int frames = 10, buffers = 8, packet_size = 0, socket_buffer = 16 << 20;
    double seconds = 0, exposure = -1, gain = -1, frame_rate = -1, timeout = 3, pair_ms = 2, loss = 0;
    long long packet_delay = -1;
    bool packet_socket = false;
  };
  auto o = std::make_shared<Options>();
  sub->add_option("--camera", o->cameras, "device id or IP address (give it twice for a stereo pair)");
  sub->add_option("--replay", o->replay, "replay a dataset manifest or a folder of images instead of a camera");
  sub->add_option("--simulate", o->simulate,
                  "serve a rendered dataset through Aravis' GigE Vision simulator (127.0.0.1, and 127.0.0.2 for a "
                  "second unit) and capture it over the protocol");
  sub->add_option("--simulate-loss", o->loss, "simulator: GVSP packets dropped on purpose (0.01 = 1 %)")
      ->capture_default_str();
  sub->add_option("--units", o->units, "unit names, one per camera (default: unit0, unit1; --simulate: the dataset's)");
  sub->add_option("-n,--frames", o->frames, "frames (pairs) to write")->capture_default_str();
  sub->add_option("--seconds", o->seconds, "stop after this long (0: no limit)")->capture_default_str();
  sub->add_option("--pixel-format", o->pixel_format, "Mono8 | BayerRG8 | Mono16")->capture_default_str();
  sub->add_option("--exposure-us", o->exposure, "exposure time, microseconds (default: the camera's)");
  sub->add_option("--gain", o->gain, "gain (default: the camera's)");
  sub->add_option("--frame-rate", o->frame_rate, "free-running frame rate, Hz (default: the camera's)");
  sub->add_option("--region", o->region, "WxH+X+Y (default: the full sensor)");
  sub->add_option("--packet-size", o->packet_size, "GigE Vision packet size, bytes (default: the camera's)");
  sub->add_option("--packet-delay-ns", o->packet_delay, "inter-packet delay, ns (default: the camera's)");
  sub->add_option("--socket-buffer", o->socket_buffer, "receive socket buffer, bytes (0: automatic)")
      ->capture_default_str();
  sub->add_option("--buffers", o->buffers, "stream buffer pool")->capture_default_str();
  sub->add_option("--trigger", o->trigger, "free | software | Line0 ...")->capture_default_str();
  sub->add_option("--feature", o->features, "generic GenICam feature NAME=VALUE (repeatable, e.g. PtpEnable=true)");
  sub->add_flag("--packet-socket", o->packet_socket, "use Aravis' packet socket (needs privileges; off in containers)");
  sub->add_option("--timeout", o->timeout, "seconds to wait for a frame")->capture_default_str();
  sub->add_option("--pair-tolerance-ms", o->pair_ms, "two cameras: timestamps of a pair differ by at most this")
      ->capture_default_str();
  sub->add_option("-o,--out", o->out, "dataset folder (must not exist or be empty)")->capture_default_str();
  return [o, global]() {
    const int kinds = int(!o->cameras.empty()) + int(!o->replay.empty()) + int(!o->simulate.empty());
    HOVS_REQUIRE(kinds == 1, "hovs capture", "give exactly one of --camera, --replay and --simulate");
    hw::CaptureSettings s;
    s.pixel_format = o->pixel_format, s.exposure_us = o->exposure, s.gain = o->gain, s.frame_rate = o->frame_rate;
    s.packet_size = o->packet_size, s.packet_delay_ns = o->packet_delay, s.socket_buffer_bytes = o->socket_buffer;
    s.buffers = o->buffers, s.trigger = o->trigger, s.packet_socket = o->packet_socket;
    if (!o->region.empty()) {
      char x = 0, p1 = 0, p2 = 0;
      HOVS_REQUIRE(std::sscanf(o->region.c_str(), "%d%c%d%c%d%c%d", &s.width, &x, &s.height, &p1, &s.offset_x, &p2,
                               &s.offset_y) == 7 && x == 'x' && p1 == '+' && p2 == '+',
                   "--region", "expected WxH+X+Y (got '", o->region, "')");
    }
    for (const auto& f : o->features) {
      const auto eq = f.find('=');
      HOVS_REQUIRE(eq != std::string::npos && eq > 0, "--feature", "expected NAME=VALUE (got '", f, "')");
      s.features.emplace_back(f.substr(0, eq), f.substr(eq + 1));
    }
    s.Check("hovs capture");
    HOVS_REQUIRE(!fs::exists(o->out) || fs::is_empty(o->out), o->out,
                 "the output folder exists and is not empty (captures are never mixed)");

    std::vector<std::unique_ptr<hw::FakeGigECamera>> simulators;
    std::vector<std::unique_ptr<hw::CameraSource>> sources;
    hw::CaptureOptions co;
    co.frames = o->frames, co.max_seconds = o->seconds, co.grab_timeout_s = o->timeout;
    co.pair_tolerance_ns = static_cast<uint64_t>(o->pair_ms * 1e6);
    co.software_trigger = o->trigger == "software";
    co.progress = !global->quiet;
    co.unit_names = o->units;
    if (!o->simulate.empty()) {
      const auto m = LoadDatasetManifest(o->simulate);
      // The units that have images (a monocular set keeps its other unit only as an occluder), at most two.
      std::vector<std::string> imaged;
      for (const auto& u : m["units"]) {
        bool has = false;
        for (const auto& fr : m["frames"])
          for (const auto& v : fr["views"]) has = has || v["unit"] == u["name"];
        if (has && imaged.size() < 2) imaged.push_back(u["name"]);
      }
      const size_t n = imaged.size();
      HOVS_REQUIRE(n > 0, o->simulate, "no images to serve");
      HOVS_REQUIRE(o->units.empty() || o->units.size() == n, "--units", "one name per simulated unit (", n, ")");
      for (size_t k = 0; k < n; ++k) {
        const std::string unit = imaged[k], address = k == 0 ? "127.0.0.1" : "127.0.0.2";
        simulators.push_back(std::make_unique<hw::FakeGigECamera>(
            address, "HOVS-SIM-" + unit, SimulatorFrames(m, o->simulate, unit, o->pixel_format), o->loss));
        sources.push_back(hw::OpenAravisCamera(address, s));
        if (o->units.empty()) co.unit_names.push_back(unit);
      }
      // The simulators start at 25 fps on their own clocks; pairs are a period apart at most.
      if (n == 2) co.pair_tolerance_ns = std::max<uint64_t>(co.pair_tolerance_ns, 20'000'000);
    } else if (!o->replay.empty()) {
      sources.push_back(hw::OpenReplay(o->replay, o->units.empty() ? "" : o->units[0], o->pixel_format, false));
    } else {
      for (const auto& id : o->cameras) sources.push_back(hw::OpenAravisCamera(id, s));
    }
    std::vector<hw::CameraSource*> raw;
    for (auto& x : sources) raw.push_back(x.get());
    g_stop.store(false);
    auto previous = std::signal(SIGINT, OnSigint);
    hw::CaptureResult r;
    try {
      r = hw::CaptureDataset(raw, co, o->out, design::DesignVersions(), &g_stop);
    } catch (...) {
      std::signal(SIGINT, previous);
      throw;
    }
    std::signal(SIGINT, previous);
    if (global->json) {
      std::cout << r.manifest.dump(1) << "\n";
    } else if (!global->quiet) {
      std::printf("hovs capture: %d frames written, %d incomplete (not written), %llu unpaired%s -> %s/dataset.json\n",
                  r.written, r.incomplete, static_cast<unsigned long long>(r.unpaired),
                  r.interrupted ? ", interrupted" : "", o->out.c_str());
    }
    return 0;
  };
}

}  // namespace hovs::apps
