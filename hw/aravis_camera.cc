// The Aravis 0.8 camera source.
#include <arv.h>
#include <arpa/inet.h>
#include <cmath>
#include <dirent.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <chrono>
#include <cstdlib>
#include <cstring>

#include "core/error.h"
#include "hw/camera_source.h"

namespace hovs::hw {

void CaptureSettings::Check(const std::string& where) const {
  HOVS_REQUIRE(pixel_format == "Mono8" || pixel_format == "BayerRG8" || pixel_format == "Mono16", where,
               "unsupported pixel format '", pixel_format, "' (Mono8, BayerRG8, Mono16)");
  HOVS_REQUIRE(width >= 0 && height >= 0 && offset_x >= 0 && offset_y >= 0, where, "region must not be negative");
  HOVS_REQUIRE(buffers >= 2 && buffers <= 256, where, "buffers must lie in [2, 256] (got ", buffers, ")");
  HOVS_REQUIRE(trigger == "free" || trigger == "software" || trigger.rfind("Line", 0) == 0, where,
               "trigger must be free, software or a line name like Line0 (got '", trigger, "')");
  HOVS_REQUIRE(packet_size == 0 || (packet_size >= 576 && packet_size <= 16384), where,
               "packet size must lie in [576, 16384] bytes (got ", packet_size, ")");
  HOVS_REQUIRE(socket_buffer_bytes >= 0, where, "socket buffer size must not be negative");
}

nlohmann::json StreamStats::ToJson() const {
  return {{"completed", completed},           {"failures", failures},
          {"underruns", underruns},           {"missing_packets", missing_packets},
          {"resent_packets", resent_packets}, {"incomplete_seen", incomplete_seen}};
}

namespace {

uint64_t MonotonicNs() {
  return static_cast<uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
          .count());
}

// Throws when err is set, with the camera and the step in the message; frees err.
void Check(GError* err, const std::string& camera, const std::string& what) {
  if (!err) return;
  const std::string msg = err->message ? err->message : "unknown error";
  g_error_free(err);
  throw Error("camera " + camera, what + ": " + msg);
}

// Aravis 0.8 sizes a stream socket's receive buffer only when the first packet of the first frame arrives
// (arvgvstream.c: _find_frame_data calls _update_socket); until then the socket has the system default
// (net.core.rmem_default, 208 kB on Debian 12), so a camera whose first frame arrives faster than the stream
// thread reads it (the simulator on a loopback, a 10 GbE camera) loses packets of that frame: the loopback
// test lost its first 688 x 550 frame on every run, with UDP RcvbufErrors in /proc/net/snmp rising during that
// frame only. So the stream's UDP socket (the one bound to its port among this process's descriptors) is sized
// before acquisition starts. Returns how many sockets were sized (0: not found, and the first frame may be lost
// as before).
int PresizeStreamSocket(uint16_t port, int bytes) {
  DIR* dir = opendir("/proc/self/fd");
  if (!dir) return 0;
  int sized = 0;
  while (const dirent* e = readdir(dir)) {
    char* end = nullptr;
    const long fd = std::strtol(e->d_name, &end, 10);
    if (end == e->d_name || *end != '\0' || fd == dirfd(dir)) continue;
    sockaddr_in a{};
    socklen_t len = sizeof(a);
    int type = 0;
    socklen_t type_len = sizeof(type);
    if (getsockname(static_cast<int>(fd), reinterpret_cast<sockaddr*>(&a), &len) != 0 || a.sin_family != AF_INET ||
        ntohs(a.sin_port) != port)
      continue;
    if (getsockopt(static_cast<int>(fd), SOL_SOCKET, SO_TYPE, &type, &type_len) != 0 || type != SOCK_DGRAM) continue;
    if (setsockopt(static_cast<int>(fd), SOL_SOCKET, SO_RCVBUF, &bytes, sizeof(bytes)) == 0) ++sized;
  }
  closedir(dir);
  return sized;
}

const char* StatusName(ArvBufferStatus s) {
  switch (s) {
    case ARV_BUFFER_STATUS_SUCCESS: return "success";
    case ARV_BUFFER_STATUS_CLEARED: return "cleared";
    case ARV_BUFFER_STATUS_TIMEOUT: return "timeout";
    case ARV_BUFFER_STATUS_MISSING_PACKETS: return "missing packets";
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID: return "wrong packet id";
    case ARV_BUFFER_STATUS_SIZE_MISMATCH: return "size mismatch";
    case ARV_BUFFER_STATUS_FILLING: return "filling";
    case ARV_BUFFER_STATUS_ABORTED: return "aborted";
    default: return "unknown";
  }
}

class AravisCamera : public CameraSource {
 public:
  AravisCamera(const std::string& id, const CaptureSettings& s) : id_(id), settings_(s) {
    s.Check("camera " + id);
    try {
      Configure();
    } catch (...) {
      // Release the control channel at once: a camera left open keeps its exclusive control privilege.
      if (camera_) g_object_unref(camera_);
      camera_ = nullptr;
      throw;
    }
  }

  void Configure() {
    const std::string& id = id_;
    const CaptureSettings& s = settings_;
    GError* err = nullptr;
    camera_ = arv_camera_new(id.c_str(), &err);
    if (!camera_) {
      std::string msg = err && err->message ? err->message : "no such device";
      if (err) g_error_free(err);
      throw Error("camera " + id, "not found (" + msg + "); list cameras with arv-tool-0.8");
    }
    Check(err, id, "open");
    const bool gv = arv_camera_is_gv_device(camera_);
    if (gv) {
      arv_camera_gv_set_stream_options(
          camera_, s.packet_socket ? ARV_GV_STREAM_OPTION_NONE : ARV_GV_STREAM_OPTION_PACKET_SOCKET_DISABLED);
      if (s.packet_size > 0) {
        arv_camera_gv_set_packet_size(camera_, s.packet_size, &err);
        Check(err, id, "packet size " + std::to_string(s.packet_size));
      }
      if (s.packet_delay_ns >= 0) {
        arv_camera_gv_set_packet_delay(camera_, s.packet_delay_ns, &err);
        Check(err, id, "packet delay");
      }
    }
    // Pixel format: only those hovs can process, and only if the camera offers it.
    guint n = 0;
    const char** formats = arv_camera_dup_available_pixel_formats_as_strings(camera_, &n, &err);
    Check(err, id, "pixel formats");
    bool offered = false;
    std::string list;
    for (guint k = 0; k < n; ++k) {
      offered = offered || s.pixel_format == formats[k];
      list += std::string(k ? ", " : "") + formats[k];
    }
    g_free(formats);
    HOVS_REQUIRE(offered, "camera " + id, "pixel format ", s.pixel_format, " is not offered (the camera has: ", list,
                 ")");
    arv_camera_set_pixel_format_from_string(camera_, s.pixel_format.c_str(), &err);
    Check(err, id, "pixel format " + s.pixel_format);
    if (s.width > 0 || s.height > 0 || s.offset_x > 0 || s.offset_y > 0) {
      gint sw = 0, sh = 0;
      arv_camera_get_sensor_size(camera_, &sw, &sh, &err);
      Check(err, id, "sensor size");
      const int w = s.width > 0 ? s.width : sw - s.offset_x, h = s.height > 0 ? s.height : sh - s.offset_y;
      HOVS_REQUIRE(s.offset_x + w <= sw && s.offset_y + h <= sh, "camera " + id, "region ", w, "x", h, "+", s.offset_x,
                   "+", s.offset_y, " exceeds the ", sw, "x", sh, " sensor");
      arv_camera_set_region(camera_, s.offset_x, s.offset_y, w, h, &err);
      Check(err, id, "region");
    }
    if (s.exposure_us >= 0) {
      arv_camera_set_exposure_time(camera_, s.exposure_us, &err);
      Check(err, id, "exposure");
    }
    if (s.gain >= 0) {
      arv_camera_set_gain(camera_, s.gain, &err);
      Check(err, id, "gain");
    }
    if (s.trigger == "free") {
      arv_camera_clear_triggers(camera_, &err);
      Check(err, id, "free running (clear triggers)");
      if (s.frame_rate > 0) {
        arv_camera_set_frame_rate(camera_, s.frame_rate, &err);
        Check(err, id, "frame rate");
      }
    } else {
      arv_camera_set_trigger(camera_, s.trigger == "software" ? "Software" : s.trigger.c_str(), &err);
      Check(err, id, "trigger " + s.trigger);
    }
    for (const auto& [name, value] : s.features) SetFeature(name, value);
  }

  ~AravisCamera() override {
    try {
      Stop();
    } catch (...) {}
    if (stream_) g_object_unref(stream_);
    if (camera_) g_object_unref(camera_);
  }

  void SetFeature(const std::string& name, const std::string& value) {
    ArvDevice* dev = arv_camera_get_device(camera_);
    ArvGcNode* node = arv_device_get_feature(dev, name.c_str());
    HOVS_REQUIRE(node && ARV_IS_GC_FEATURE_NODE(node), "camera " + id_, "has no GenICam feature '", name, "'");
    GError* err = nullptr;
    if (ARV_IS_GC_COMMAND(node)) {
      arv_gc_command_execute(ARV_GC_COMMAND(node), &err);
    } else {
      arv_gc_feature_node_set_value_from_string(ARV_GC_FEATURE_NODE(node), value.c_str(), &err);
    }
    Check(err, id_, "feature " + name + " = " + value);
    applied_features_[name] = value;
  }

  nlohmann::json Info() const override {
    GError* err = nullptr;
    auto str = [&](const char* v) { return std::string(v ? v : ""); };
    nlohmann::json j = {{"id", id_},
                        {"vendor", str(arv_camera_get_vendor_name(camera_, &err))},
                        {"model", str(arv_camera_get_model_name(camera_, &err))},
                        {"serial", str(arv_camera_get_device_serial_number(camera_, &err))},
                        {"pixel_format", settings_.pixel_format},
                        {"trigger", settings_.trigger}};
    if (err) g_error_free(err), err = nullptr;
    gint x = 0, y = 0, w = 0, h = 0;
    arv_camera_get_region(camera_, &x, &y, &w, &h, &err);
    if (!err)
      j["region"] = {x, y, w, h};
    else
      g_error_free(err), err = nullptr;
    const double exposure = arv_camera_get_exposure_time(camera_, &err);
    if (!err)
      j["exposure_us"] = exposure;
    else
      g_error_free(err), err = nullptr;
    const double gain = arv_camera_get_gain(camera_, &err);
    if (!err)
      j["gain"] = gain;
    else
      g_error_free(err), err = nullptr;
    if (arv_camera_is_gv_device(camera_)) {
      const int ps = arv_camera_gv_get_packet_size(camera_, &err);
      if (!err)
        j["packet_size"] = ps;
      else
        g_error_free(err), err = nullptr;
    }
    j["features"] = applied_features_;
    if (stream_ && ARV_IS_GV_STREAM(stream_)) j["stream_socket_presized"] = socket_presized_;
    return j;
  }

  void Start() override {
    HOVS_REQUIRE(!running_, "camera " + id_, "already started");
    GError* err = nullptr;
    if (!stream_) {
      stream_ = arv_camera_create_stream(camera_, nullptr, nullptr, &err);
      Check(err, id_, "create stream");
      HOVS_REQUIRE(stream_, "camera " + id_, "cannot create a stream");
      if (ARV_IS_GV_STREAM(stream_)) {
        if (settings_.socket_buffer_bytes > 0)
          g_object_set(stream_, "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED, "socket-buffer-size",
                       settings_.socket_buffer_bytes, nullptr);
        g_object_set(stream_, "packet-resend",
                     settings_.packet_resend ? ARV_GV_STREAM_PACKET_RESEND_ALWAYS : ARV_GV_STREAM_PACKET_RESEND_NEVER,
                     nullptr);
      }
      const guint payload = arv_camera_get_payload(camera_, &err);
      Check(err, id_, "payload size");
      for (int k = 0; k < settings_.buffers; ++k) arv_stream_push_buffer(stream_, arv_buffer_new(payload, nullptr));
      // The size Aravis itself will give the socket at the first frame (fixed, or the payload when automatic).
      if (ARV_IS_GV_STREAM(stream_))
        socket_presized_ = PresizeStreamSocket(arv_gv_stream_get_port(ARV_GV_STREAM(stream_)),
                                               settings_.socket_buffer_bytes > 0 ? settings_.socket_buffer_bytes
                                                                                 : static_cast<int>(payload)) > 0;
    }
    arv_camera_start_acquisition(camera_, &err);
    Check(err, id_, "start acquisition");
    running_ = true;
  }

  std::optional<Frame> Grab(double timeout_s) override {
    HOVS_REQUIRE(running_, "camera " + id_, "Grab before Start");
    // (A NaN or negative timeout became a GLib assertion inside Aravis: checked here, for every caller.)
    HOVS_REQUIRE(std::isfinite(timeout_s) && timeout_s > 0 && timeout_s <= 3600, "camera " + id_,
                 "the frame timeout must be in (0, 3600] s (got ", timeout_s, ")");
    ArvBuffer* b = arv_stream_timeout_pop_buffer(stream_, static_cast<guint64>(timeout_s * 1e6));
    if (!b) return std::nullopt;
    Frame f;
    const ArvBufferStatus st = arv_buffer_get_status(b);
    f.complete = st == ARV_BUFFER_STATUS_SUCCESS;
    f.status = StatusName(st);
    f.frame_id = arv_buffer_get_frame_id(b);
    f.device_ns = arv_buffer_get_timestamp(b);
    f.system_ns = MonotonicNs();
    f.pixel_format = settings_.pixel_format;
    if (f.complete && arv_buffer_get_payload_type(b) == ARV_BUFFER_PAYLOAD_TYPE_IMAGE) {
      f.width = arv_buffer_get_image_width(b), f.height = arv_buffer_get_image_height(b);
      size_t size = 0;
      const auto* data = static_cast<const uint8_t*>(arv_buffer_get_data(b, &size));
      const size_t need = size_t(f.width) * f.height * f.BytesPerPixel();
      if (size >= need)
        f.data.assign(data, data + need);
      else
        f.complete = false, f.status = "short image payload";
    } else if (f.complete) {
      f.complete = false, f.status = "not an image payload";
    }
    if (!f.complete) ++incomplete_;
    arv_stream_push_buffer(stream_, b);
    return f;
  }

  void SoftwareTrigger() override {
    HOVS_REQUIRE(settings_.trigger == "software", "camera " + id_, "software trigger needs --trigger software");
    GError* err = nullptr;
    arv_camera_software_trigger(camera_, &err);
    Check(err, id_, "software trigger");
  }

  void Stop() override {
    if (!running_) return;
    GError* err = nullptr;
    arv_camera_stop_acquisition(camera_, &err);
    running_ = false;
    Check(err, id_, "stop acquisition");
  }

  StreamStats Stats() const override {
    StreamStats s;
    s.incomplete_seen = incomplete_;
    if (!stream_) return s;
    guint64 c = 0, f = 0, u = 0;
    arv_stream_get_statistics(stream_, &c, &f, &u);
    s.completed = c, s.failures = f, s.underruns = u;
    if (ARV_IS_GV_STREAM(stream_)) {
      guint64 resent = 0, missing = 0;
      arv_gv_stream_get_statistics(ARV_GV_STREAM(stream_), &resent, &missing);
      s.resent_packets = resent, s.missing_packets = missing;
    }
    return s;
  }

 private:
  std::string id_;
  CaptureSettings settings_;
  ArvCamera* camera_ = nullptr;
  ArvStream* stream_ = nullptr;
  bool running_ = false;
  bool socket_presized_ = false;  // the stream socket sized before the first frame (PresizeStreamSocket)
  uint64_t incomplete_ = 0;
  std::map<std::string, std::string> applied_features_;
};

}  // namespace

std::unique_ptr<CameraSource> OpenAravisCamera(const std::string& id, const CaptureSettings& settings) {
  return std::make_unique<AravisCamera>(id, settings);
}

std::map<std::string, std::string> HwVersions() {
  return {{"aravis", std::to_string(arv_get_major_version()) + "." + std::to_string(arv_get_minor_version()) + "." +
                         std::to_string(arv_get_micro_version())}};
}

}  // namespace hovs::hw
