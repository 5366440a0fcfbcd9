// Frame sources: GigE Vision cameras through Aravis 0.8, and the replay of a dataset folder. Capture, live
// expansion and the tests use one interface, so the same code runs on a camera, on Aravis' GigE Vision simulator
// and on files.
//
// Conventions: images are row-major, tightly packed; Mono8 / BayerRG8 one byte per pixel, Mono16 two bytes
// (little-endian). Timestamps in nanoseconds: device_ns from the camera's clock (GigE Vision timestamp), system_ns
// from the host's monotonic clock when the frame was completed.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace hovs::hw {

struct CaptureSettings {
  std::string pixel_format = "Mono8";  // Mono8 | BayerRG8 | Mono16
  double exposure_us = -1;             // < 0: leave the camera's value
  double gain = -1;                    // < 0: leave
  double frame_rate = -1;              // < 0: leave
  int width = 0, height = 0;           // region; 0: the full sensor
  int offset_x = 0, offset_y = 0;
  int packet_size = 0;                 // GigE Vision packet size, bytes; 0: leave
  int64_t packet_delay_ns = -1;        // inter-packet delay; < 0: leave
  int socket_buffer_bytes = 16 << 20;  // receive socket buffer (capped by net.core.rmem_max); 0: Aravis' automatic size
  int buffers = 8;                     // the stream's buffer pool
  std::string trigger = "free";        // free | software | Line0 (hardware line)
  bool packet_socket = false;          // Aravis' packet socket (needs capabilities; fails in containers)
  bool packet_resend = true;
  std::vector<std::pair<std::string, std::string>> features;  // generic GenICam features, set in order (PTP...)
  void Check(const std::string& where) const;
};

struct Frame {
  std::vector<uint8_t> data;
  int width = 0, height = 0;
  std::string pixel_format;
  uint64_t frame_id = 0;
  uint64_t device_ns = 0, system_ns = 0;
  bool complete = false;  // false: the stream reported an incomplete / failed buffer (never written as good)
  std::string status;     // "success" or Aravis' reason
  size_t BytesPerPixel() const { return pixel_format == "Mono16" ? 2 : 1; }
};

struct StreamStats {
  uint64_t completed = 0, failures = 0, underruns = 0;  // buffers
  uint64_t missing_packets = 0, resent_packets = 0;     // GigE Vision
  uint64_t incomplete_seen = 0;                         // incomplete frames handed out by Grab
  nlohmann::json ToJson() const;
};

class CameraSource {
 public:
  virtual ~CameraSource() = default;
  virtual nlohmann::json Info() const = 0;  // vendor, model, serial, address, settings actually applied
  virtual void Start() = 0;
  // The next frame, or nothing after timeout_s. An incomplete frame is returned with complete = false.
  virtual std::optional<Frame> Grab(double timeout_s) = 0;
  virtual void SoftwareTrigger() = 0;  // throws if the source is not in software-trigger mode
  virtual void Stop() = 0;
  virtual StreamStats Stats() const = 0;
};

// Opens a GigE Vision camera by device id ("Vendor-Model-Serial", as arv-tool lists it) or by IP address.
// Throws hovs::Error naming the camera: not found, unsupported pixel format, a feature that cannot be set.
std::unique_ptr<CameraSource> OpenAravisCamera(const std::string& id, const CaptureSettings& settings);

// Versions of the libraries capture uses beside the core's: "aravis" (the one loaded).
std::map<std::string, std::string> HwVersions();

// Replays the images of one unit of a dataset manifest (or every image of a folder, sorted) as frames, with the
// manifest's timestamps when it has them. pixel_format: Mono8 (grey conversion) or BayerRG8 (the file is a
// mosaic already) .
std::unique_ptr<CameraSource> OpenReplay(const std::filesystem::path& dataset_or_folder, const std::string& unit,
                                         const std::string& pixel_format, bool loop);

// Pairs frames of two streams by device timestamp: frames whose timestamps differ by at most tolerance_ns.
struct FramePairer {
  uint64_t tolerance_ns = 2'000'000;
  // Adds a frame of stream 0 or 1; returns the pairs completed by it (oldest first). Unpaired frames older than
  // the newest pair are dropped and counted.
  std::vector<std::pair<Frame, Frame>> Add(int stream, Frame frame);
  uint64_t dropped = 0;

 private:
  std::vector<Frame> pending_[2];
};

}  // namespace hovs::hw
