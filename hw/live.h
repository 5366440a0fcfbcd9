// The live loop: frames from a source expanded into the views of a mapping as they arrive (a raw BayerRG8 frame
// goes straight to RGB views, demosaiced inside the remap), every Nth frame's views written, each shown through
// a caller's display, with the latency of every stage.
#pragma once

#include <atomic>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "hw/camera_source.h"
#include "unwrap/remap.h"
#include "unwrap/remap_table.h"
#include "unwrap/rig_mapping.h"

namespace hovs::hw {

struct LiveOptions {
  int frames = 100;     // 0: until stopped or `seconds`
  double seconds = 0;   // 0: no limit
  double timeout = 3;   // s: a complete frame must arrive within this of the previous one
  int write_every = 0;  // write the views of every Nth frame into out_dir (0: never)
  std::filesystem::path out_dir;
  bool software_trigger = false;
  bool replay = false;                    // the source ends (a replay): no frame is the end, not a timeout
  std::string source_name, mapping_name;  // named in errors
  unwrap::PixelFormat format = unwrap::PixelFormat::kGray8;
  unwrap::Interpolation interpolation = unwrap::Interpolation::kBilinear;
};

struct LiveRun {
  int processed = 0, incomplete = 0, written = 0;
  double seconds = 0;
  // Per processed frame, ms: waiting for the frame, the remap, writing (when written), the display (with one),
  // and from the frame's arrival to its output.
  std::vector<double> wait_ms, remap_ms, write_ms, display_ms, total_ms;
  std::vector<double> sink_ms;  // handing the views to the sink (with one)
};

// Takes each processed frame's views after the display, with the frame's arrival time (ns since the Unix epoch);
// it may swap *views for buffers of the same sizes (the DDS publisher hands back an older frame's).
using LiveSink = std::function<void(uint64_t stamp_ns, std::vector<unwrap::Image8>* views)>;

// Writes views as dir/<stem>_<names[v]>.png (8 bits); the two writers below name them from their mapping.
void WriteNamedViews(const std::filesystem::path& dir, const std::string& stem, const std::vector<std::string>& names,
                     const std::vector<unwrap::Image8>& views);

// Writes the views of one frame as dir/<stem>_<view>.png (8 bits).
void WriteLiveViews(const std::filesystem::path& dir, const std::string& stem, const unwrap::RemapTable& table,
                    const std::vector<unwrap::Image8>& views);

// Runs until `frames` frames are processed, `seconds` pass, the replay ends or *stop is set (Ctrl-C; the display
// may set it too). Starts and stops the camera; throws hovs::Error naming the source when no complete frame
// arrives in time or a frame does not match the mapping's size.
LiveRun RunLive(CameraSource& camera, const unwrap::RemapTable& table, const LiveOptions& options,
                std::atomic<bool>* stop, const std::function<void(const std::vector<unwrap::Image8>&)>& display = {},
                const LiveSink& sink = {});

// Two units in one pipeline: frames of two sources paired by device timestamp (FramePairer, within
// pair_tolerance_ns), each pair expanded by the rig mapping into all its views in one pass, then written,
// displayed and handed to the sink as RunLive does. Each source is grabbed on a thread of its own. Frames whose
// partner never arrives are counted (unpaired), never expanded alone; pairs that arrive while the pipeline is
// still busy with two waiting ones replace the older (counted as dropped pairs), except in a replay, which has no
// deadline and waits. Throws naming the unit whose frame does not fit the mapping, or when the pair's pixel
// formats differ.
// Takes each processed pair's raw frames after the views' sink; it may swap their data out (the depth thread does).
using PairFramesSink = std::function<void(uint64_t stamp_ns, Frame* left, Frame* right)>;

struct PairLiveRun {
  LiveRun live;
  uint64_t unpaired = 0;        // frames the pairer gave up on
  uint64_t dropped_pairs = 0;   // pairs replaced while the pipeline was busy
  std::vector<double> skew_ms;  // |t0 - t1| of each processed pair (device clocks)
};
PairLiveRun RunPairLive(const std::vector<CameraSource*>& cameras, const unwrap::RigMapping& mapping,
                        const LiveOptions& options, std::atomic<bool>* stop,
                        const std::function<void(const std::vector<unwrap::Image8>&)>& display = {},
                        const LiveSink& sink = {}, uint64_t pair_tolerance_ns = 2'000'000,
                        const PairFramesSink& frames_sink = {});

// Writes the views of one frame of a rig as dir/<stem>_<view>.png (8 bits).
void WriteRigLiveViews(const std::filesystem::path& dir, const std::string& stem, const unwrap::RigMapping& mapping,
                       const std::vector<unwrap::Image8>& views);

}  // namespace hovs::hw
