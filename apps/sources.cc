#include "apps/sources.h"

#include <cstdio>

#include "apps/commands.h"
#include "apps/model_files.h"
#include "core/error.h"
#include "hw/fake_gige.h"

namespace hovs::apps {
namespace {
namespace fs = std::filesystem;

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
        f.data[k] =
            im.channels == 1
                ? im.data[k]
                : static_cast<uint8_t>(
                      (299 * im.data[3 * k] + 587 * im.data[3 * k + 1] + 114 * im.data[3 * k + 2] + 500) / 1000);
      frames.push_back(std::move(f));
    }
  HOVS_REQUIRE(!frames.empty(), manifest.string(), "no images of unit '", unit, "'");
  return frames;
}

}  // namespace

std::vector<hw::CameraSource*> OpenedSources::Raw() const {
  std::vector<hw::CameraSource*> raw;
  for (const auto& s : sources) raw.push_back(s.get());
  return raw;
}

void AddSourceOptions(CLI::App* sub, SourceOptions* o) {
  sub->add_option("--camera", o->cameras, "device id or IP address (give it twice for a stereo pair)");
  sub->add_option("--replay", o->replay, "replay a dataset manifest or a folder of images instead of a camera");
  sub->add_flag("--loop", o->loop, "--replay: start again at the end");
  sub->add_option("--simulate", o->simulate,
                  "serve a rendered dataset through Aravis' GigE Vision simulator (127.0.0.1, and 127.0.0.2 for a "
                  "second unit) and take the frames over the protocol");
  AddBounded(sub, "--simulate-loss", &o->loss, "simulator: GVSP packets dropped on purpose (0.01 = 1 %)", 0,
             hw::kMaxLostPacketRatio);
  sub->add_option("--units", o->units, "unit names, one per camera (default: unit0, unit1; --simulate: the dataset's)");
  sub->add_option("--pixel-format", o->pixel_format, "Mono8 | BayerRG8 | Mono16")->capture_default_str();
  sub->add_option("--exposure-us", o->exposure, "exposure time, microseconds (default: the camera's)")
      ->check(Bounded(0, 1e8, true));
  sub->add_option("--gain", o->gain, "gain (default: the camera's)")->check(Bounded(0, 1000));
  sub->add_option("--frame-rate", o->frame_rate, "free-running frame rate, Hz (default: the camera's)")
      ->check(Bounded(0, 10000, true));
  sub->add_option("--region", o->region, "WxH+X+Y (default: the full sensor)");
  sub->add_option("--packet-size", o->packet_size, "GigE Vision packet size, bytes (default: the camera's)")
      ->check(Bounded(64, 65535));
  sub->add_option("--packet-delay-ns", o->packet_delay, "inter-packet delay, ns (default: the camera's)")
      ->check(Bounded(0, 1e9));
  AddBounded(sub, "--socket-buffer", &o->socket_buffer, "receive socket buffer, bytes (0: automatic)", 0, 1073741824);
  AddBounded(sub, "--buffers", &o->buffers, "stream buffer pool", 1, 1024);
  sub->add_option("--trigger", o->trigger, "free | software | Line0 ...")->capture_default_str();
  sub->add_option("--feature", o->features, "generic GenICam feature NAME=VALUE (repeatable, e.g. PtpEnable=true)");
  sub->add_flag("--packet-socket", o->packet_socket, "use Aravis' packet socket (needs privileges; off in containers)");
}

OpenedSources OpenSources(const SourceOptions& o) {
  const int kinds = int(!o.cameras.empty()) + int(!o.replay.empty()) + int(!o.simulate.empty());
  HOVS_REQUIRE(kinds == 1, "frame source", "give exactly one of --camera, --replay and --simulate");
  hw::CaptureSettings s;
  s.pixel_format = o.pixel_format, s.exposure_us = o.exposure, s.gain = o.gain, s.frame_rate = o.frame_rate;
  s.packet_size = o.packet_size, s.packet_delay_ns = o.packet_delay, s.socket_buffer_bytes = o.socket_buffer;
  s.buffers = o.buffers, s.trigger = o.trigger, s.packet_socket = o.packet_socket;
  if (!o.region.empty()) {
    char x = 0, p1 = 0, p2 = 0;
    int end = -1;  // nothing may follow
    HOVS_REQUIRE(std::sscanf(o.region.c_str(), "%d%c%d%c%d%c%d%n", &s.width, &x, &s.height, &p1, &s.offset_x, &p2,
                             &s.offset_y, &end) == 7 &&
                     x == 'x' && p1 == '+' && p2 == '+' && end == static_cast<int>(o.region.size()),
                 "--region", "expected WxH+X+Y (got '", o.region, "')");
    HOVS_REQUIRE(s.width >= 1 && s.height >= 1 && s.width <= 65535 && s.height <= 65535 && s.offset_x >= 0 &&
                     s.offset_y >= 0 && s.offset_x <= 65535 && s.offset_y <= 65535,
                 "--region", "needs a size of at least 1 x 1 and offsets >= 0 (got '", o.region, "')");
  }
  for (const auto& f : o.features) {
    const auto eq = f.find('=');
    HOVS_REQUIRE(eq != std::string::npos && eq > 0, "--feature", "expected NAME=VALUE (got '", f, "')");
    s.features.emplace_back(f.substr(0, eq), f.substr(eq + 1));
  }
  s.Check("camera settings");
  OpenedSources r;
  r.units = o.units;
  if (!o.simulate.empty()) {
    const auto m = LoadDatasetManifest(o.simulate);
    // The units that have images (a monocular set keeps its other unit only as an occluder), at most two.
    std::vector<std::string> imaged;
    for (const auto& u : m["units"]) {
      bool has = false;
      for (const auto& fr : m["frames"])
        for (const auto& v : fr["views"]) has = has || v["unit"] == u["name"];
      if (has && imaged.size() < 2) imaged.push_back(u["name"]);
    }
    HOVS_REQUIRE(!imaged.empty(), o.simulate, "no images to serve");
    HOVS_REQUIRE(o.units.empty() || o.units.size() == imaged.size(), "--units", "one name per simulated unit (",
                 imaged.size(), ")");
    for (size_t k = 0; k < imaged.size(); ++k) {
      const std::string address = k == 0 ? "127.0.0.1" : "127.0.0.2";
      r.simulators.push_back(std::make_unique<hw::FakeGigECamera>(
          address, "HOVS-SIM-" + imaged[k], SimulatorFrames(m, o.simulate, imaged[k], o.pixel_format), o.loss));
      r.sources.push_back(hw::OpenAravisCamera(address, s));
      if (o.units.empty()) r.units.push_back(imaged[k]);
    }
  } else if (!o.replay.empty()) {
    // With two --units, a manifest's two units replayed side by side (paired by their timestamps).
    HOVS_REQUIRE(o.units.size() <= 2, "--units", "at most two units (got ", o.units.size(), ")");
    for (size_t k = 0; k < std::max<size_t>(1, o.units.size()); ++k)
      r.sources.push_back(hw::OpenReplay(o.replay, o.units.empty() ? "" : o.units[k], o.pixel_format, o.loop));
  } else {
    HOVS_REQUIRE(o.cameras.size() <= 2, "--camera", "at most two cameras (got ", o.cameras.size(), ")");
    for (const auto& id : o.cameras) r.sources.push_back(hw::OpenAravisCamera(id, s));
  }
  for (size_t k = r.units.size(); k < r.sources.size(); ++k) r.units.push_back("unit" + std::to_string(k));
  HOVS_REQUIRE(r.units.size() == r.sources.size(), "--units", "one name per camera (", r.sources.size(), ")");
  return r;
}

std::vector<hw::CameraSource*> PairSources(const OpenedSources& src, const std::vector<std::string>& units) {
  std::string have;
  for (const auto& u : src.units) have += (have.empty() ? "" : ", ") + u;
  HOVS_REQUIRE(src.sources.size() == 2, "frame source", "the rig's views need a frame of each unit (", units[0], ", ",
               units[1], ") but there is one source (", have,
               "): give two --camera, a --simulate dataset of two units, or --replay with --units ", units[0],
               " --units ", units[1]);
  std::vector<hw::CameraSource*> out;
  for (const auto& u : units) {
    size_t k = 0;
    while (k < src.units.size() && src.units[k] != u) ++k;
    HOVS_REQUIRE(k < src.units.size(), "--units", "no source is named after the rig's unit '", u, "' (the sources are ",
                 have, ")");
    out.push_back(src.sources[k].get());
  }
  return out;
}

}  // namespace hovs::apps
