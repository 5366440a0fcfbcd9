// Capture to a dataset: the same manifest the renderer writes (dataset.json, format hovs-dataset), without
// ground truth, with per-frame metadata (device and host timestamps, frame ids, exposure, gain, serial numbers)
// and the stream statistics. Only complete frames are written; incomplete ones are counted and listed. Images
// and the manifest are written atomically (temporary file + rename) by a writer thread, and the manifest is
// rewritten after every frame it wrote, so an interrupted capture (Ctrl-C, a full disk) leaves a valid dataset
// of the frames written so far.
#pragma once

#include <atomic>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hw/camera_source.h"

namespace hovs::hw {

struct CaptureOptions {
  int frames = 10;            // frames (pairs) to write
  double max_seconds = 0;     // 0: no limit
  double grab_timeout_s = 3;  // per frame; a camera silent this long stops the capture with an error
  uint64_t pair_tolerance_ns = 2'000'000;
  bool software_trigger = false;        // trigger every camera before each frame
  std::vector<std::string> unit_names;  // one per source (default unit0, unit1)
  // Frames (pairs) grabbed but not yet written: a writer thread compresses and writes them while the grab loop
  // keeps draining the cameras' buffers; when it is full the grab loop waits (the cameras' buffer pools then
  // absorb the burst, and underruns show in the statistics).
  int write_queue = 16;
  // "png" (zlib-compressed, 8 or 16 bit) or "pgm" (binary PGM, uncompressed: written at disk speed, for full
  // frame rates; every hovs command reads both).
  std::string image_format = "png";
  bool progress = false;
  void Check(size_t sources, const std::string& where) const;
};

struct CaptureResult {
  int written = 0;
  int incomplete = 0;     // frames the stream delivered incomplete (not written)
  uint64_t unpaired = 0;  // two cameras: frames without a partner within the tolerance
  bool interrupted = false;
  int max_queue_depth = 0;  // the writer queue's high-water mark
  nlohmann::json manifest;
};

// sources: one or two started-or-not sources (Start is called here). stop: set asynchronously (SIGINT) to end
// the capture early with a valid manifest. A capture that ends (by an error or a stop) before its first frame is
// written leaves `out` as it found it (absent or empty), so that the same command can run into it again; every
// frame of a camera must have its first frame's size and pixel format.
CaptureResult CaptureDataset(const std::vector<CameraSource*>& sources, const CaptureOptions& options,
                             const std::filesystem::path& out, const nlohmann::json& versions,
                             const std::atomic<bool>* stop);

}  // namespace hovs::hw
