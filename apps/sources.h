// Frame sources named on the command line, shared by hovs capture and hovs live: GigE Vision cameras (--camera),
// a replay (--replay), or Aravis' GigE Vision simulator serving a rendered dataset (--simulate), with the camera
// settings (--pixel-format, --exposure-us, --gain, --frame-rate, --region, --packet-size, ...).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "hw/camera_source.h"
#include "hw/fake_gige.h"

namespace hovs::apps {

struct SourceOptions {
  std::vector<std::string> cameras, units, features;
  std::string replay, simulate, region, pixel_format = "Mono8", trigger = "free";
  int buffers = 8, packet_size = 0, socket_buffer = 16 << 20;
  double exposure = -1, gain = -1, frame_rate = -1, loss = 0;
  long long packet_delay = -1;
  bool packet_socket = false, loop = false;
};

struct OpenedSources {
  std::vector<std::unique_ptr<hw::FakeGigECamera>> simulators;  // --simulate: kept alive while capturing
  std::vector<std::unique_ptr<hw::CameraSource>> sources;
  std::vector<std::string> units;  // one name per source
  std::vector<hw::CameraSource*> Raw() const;
};

void AddSourceOptions(CLI::App* sub, SourceOptions* o);

// Throws hovs::Error naming the option or the camera.
OpenedSources OpenSources(const SourceOptions& o);

// The two sources of a frame pair in the rig's unit order, matched by unit name (--units names cameras and
// replays; a simulation's units are the dataset's). Throws naming what is missing.
std::vector<hw::CameraSource*> PairSources(const OpenedSources& src, const std::vector<std::string>& units);

}  // namespace hovs::apps
