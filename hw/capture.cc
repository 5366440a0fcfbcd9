#include "hw/capture.h"

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

#include "core/error.h"
#include "core/io.h"
#include "io/image_io.h"

namespace hovs::hw {
namespace fs = std::filesystem;

void CaptureOptions::Check(size_t sources, const std::string& where) const {
  HOVS_REQUIRE(sources == 1 || sources == 2, where, "capture takes one or two cameras (got ", sources, ")");
  HOVS_REQUIRE(frames >= 1, where, "frames must be at least 1 (got ", frames, ")");
  HOVS_REQUIRE(max_seconds >= 0 && std::isfinite(max_seconds), where + ".max_seconds (--seconds)", "must be >= 0 (got ",
               max_seconds, ")");
  HOVS_REQUIRE(std::isfinite(grab_timeout_s) && grab_timeout_s > 0 && grab_timeout_s <= 3600,
               where + ".grab_timeout_s (--timeout)", "must be in (0, 3600] seconds (got ", grab_timeout_s, ")");
  HOVS_REQUIRE(unit_names.empty() || unit_names.size() == sources, where, "one unit name per camera");
  HOVS_REQUIRE(write_queue >= 1 && write_queue <= 4096, where, "write_queue must be in 1..4096 (got ", write_queue,
               ")");
  HOVS_REQUIRE(image_format == "png" || image_format == "pgm", where + ".image_format", "expected png or pgm (got '",
               image_format, "')");
}

namespace {

// A binary PGM (P5): 8-bit, or 16-bit big-endian for Mono16 (the format's byte order); written atomically.
void WriteFramePgm(const fs::path& path, const Frame& f) {
  const bool wide = f.pixel_format == "Mono16";
  const size_t n = size_t(f.width) * f.height;
  std::string text =
      "P5\n" + std::to_string(f.width) + " " + std::to_string(f.height) + "\n" + (wide ? "65535" : "255") + "\n";
  const size_t head = text.size();
  text.resize(head + n * (wide ? 2 : 1));
  if (wide) {
    for (size_t k = 0; k < n; ++k)
      text[head + 2 * k] = char(f.data[2 * k + 1]), text[head + 2 * k + 1] = char(f.data[2 * k]);
  } else {
    std::memcpy(&text[head], f.data.data(), n);
  }
  WriteFileAtomic(path, text);
}

// An 8-bit one-channel PNG (Mono8 or a raw BayerRG8 mosaic), or 16-bit for Mono16; written atomically.
void WriteFrameImage(const fs::path& path, const Frame& f) {
  if (path.extension() == ".pgm") return WriteFramePgm(path, f);
  std::vector<float> v(size_t(f.width) * f.height);
  if (f.pixel_format == "Mono16") {
    for (size_t k = 0; k < v.size(); ++k) v[k] = float(f.data[2 * k] | (f.data[2 * k + 1] << 8)) / 65535.f;
  } else {
    for (size_t k = 0; k < v.size(); ++k) v[k] = f.data[k] / 255.f;
  }
  io::WriteImage(path, f.width, f.height, 1, v, f.pixel_format == "Mono16" ? 16 : 8);
}

}  // namespace

CaptureResult CaptureDataset(const std::vector<CameraSource*>& sources, const CaptureOptions& o, const fs::path& out,
                             const nlohmann::json& versions, const std::atomic<bool>* stop) {
  o.Check(sources.size(), "capture");
  // A capture that ends before its first frame is written leaves nothing behind (the folder as it was: absent or
  // empty), so that the same command can run again into it; one with frames keeps them, with its manifest.
  const bool created = !fs::exists(out);
  struct RemoveIfEmptyCapture {
    const fs::path& out;
    bool created;
    const int* written;
    bool armed = true;
    ~RemoveIfEmptyCapture() {
      if (!armed || *written > 0) return;
      std::error_code ec;
      if (created) {
        fs::remove_all(out, ec);
      } else {
        for (const char* f : {"images", "dataset.json", kOutputMarker}) fs::remove_all(out / f, ec);
      }
    }
  };
  CaptureResult r;
  RemoveIfEmptyCapture cleanup{out, created, &r.written};
  fs::create_directories(out / "images");
  WriteOutputMarker(out, "capture");
  std::vector<std::string> names = o.unit_names;
  for (size_t k = names.size(); k < sources.size(); ++k) names.push_back("unit" + std::to_string(k));
  nlohmann::json units = nlohmann::json::array();
  for (size_t k = 0; k < sources.size(); ++k) units.push_back({{"name", names[k]}, {"camera", sources[k]->Info()}});
  nlohmann::json& m = r.manifest;
  m = {{"format", "hovs-dataset"},
       {"version", 1},
       {"kind", "capture"},
       {"name", "capture"},
       {"generator", "hovs capture"},
       {"versions", versions},
       {"units", units},
       {"frames", nlohmann::json::array()},
       {"incomplete_frames", nlohmann::json::array()},
       {"status", "capturing"},
       {"note", "real capture: no ground truth; images are raw sensor data (Mono8, BayerRG8 mosaic or Mono16)"}};
  // m, the statistics snapshot and r.written are shared by the grab loop and the writer thread: guarded by mu.
  std::mutex mu;
  nlohmann::json stats = nlohmann::json::object();
  auto snapshot_stats = [&]() {
    nlohmann::json st = nlohmann::json::object();
    for (size_t k = 0; k < sources.size(); ++k) st[names[k]] = sources[k]->Stats().ToJson();
    std::lock_guard<std::mutex> lock(mu);
    stats = st;
  };
  auto write_manifest_locked = [&]() {
    m["statistics"] = stats;
    m["unpaired_frames"] = r.unpaired;
    m["writer"] = {{"queue_capacity", o.write_queue}, {"max_queue_depth", r.max_queue_depth}};
    WriteFileAtomic(out / "dataset.json", m.dump(1) + "\n");
  };
  snapshot_stats();
  {
    std::lock_guard<std::mutex> lock(mu);
    write_manifest_locked();
  }
  for (auto* s : sources) s->Start();
  const auto t0 = std::chrono::steady_clock::now();
  FramePairer pairer;
  pairer.tolerance_ns = o.pair_tolerance_ns;
  auto view_json = [&](size_t unit, const Frame& f, const std::string& rel) {
    const auto info = sources[unit]->Info();
    nlohmann::json v = {{"unit", names[unit]},
                        {"image", rel},
                        {"frame_id", f.frame_id},
                        {"device_ns", f.device_ns},
                        {"system_ns", f.system_ns},
                        {"pixel_format", f.pixel_format},
                        {"width", f.width},
                        {"height", f.height},
                        {"serial", info.value("serial", "")}};
    if (info.contains("exposure_us")) v["exposure_us"] = info["exposure_us"];
    if (info.contains("gain")) v["gain"] = info["gain"];
    return v;
  };
  // The writer: takes sets in order, writes their images, then lists them in the manifest.
  struct Pending {
    int id;
    std::vector<Frame> frames;
    std::vector<nlohmann::json> views;
  };
  std::deque<Pending> queue;
  std::condition_variable not_empty, not_full;
  bool closing = false;
  std::exception_ptr writer_error;
  std::thread writer([&] {
    for (;;) {
      Pending p;
      {
        std::unique_lock<std::mutex> lock(mu);
        not_empty.wait(lock, [&] { return !queue.empty() || closing; });
        if (queue.empty()) return;
        p = std::move(queue.front());
        queue.pop_front();
      }
      not_full.notify_one();
      try {
        nlohmann::json frame = {{"id", p.id}, {"views", nlohmann::json::array()}};
        for (size_t k = 0; k < p.frames.size(); ++k) {
          WriteFrameImage(out / p.views[k]["image"].get<std::string>(), p.frames[k]);
          frame["views"].push_back(p.views[k]);
        }
        std::lock_guard<std::mutex> lock(mu);
        m["frames"].push_back(frame);
        ++r.written;
        write_manifest_locked();
        if (o.progress) std::fprintf(stderr, "\rcapture: %d / %d frames", r.written, o.frames);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mu);
        writer_error = std::current_exception();
        closing = true;
        queue.clear();
        not_full.notify_all();
        return;
      }
    }
  });
  auto finish_writer = [&]() {
    {
      std::lock_guard<std::mutex> lock(mu);
      closing = true;
    }
    not_empty.notify_all();
    if (writer.joinable()) writer.join();
  };
  int queued = 0;
  // Every wait is bounded overall: a frame set must be queued within grab_timeout_s of the previous one (or of
  // the start), whatever the cameras deliver meanwhile (incomplete frames, frames without a partner).
  auto last_progress = std::chrono::steady_clock::now();
  std::vector<Frame> first_frame(sources.size());  // size and pixel format only
  try {
    while (queued < o.frames) {
      {
        std::lock_guard<std::mutex> lock(mu);
        if (writer_error) break;
      }
      if (stop && stop->load()) {
        r.interrupted = true;
        break;
      }
      if (o.max_seconds > 0 &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > o.max_seconds)
        break;
      {
        const double idle = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_progress).count();
        HOVS_REQUIRE(idle <= o.grab_timeout_s, "capture", "no complete frame", sources.size() > 1 ? " pair" : "",
                     " within ", o.grab_timeout_s, " s (", r.incomplete, " incomplete frames, ", r.unpaired,
                     " without a partner; --timeout sets the wait)");
      }
      if (o.software_trigger)
        for (auto* s : sources) s->SoftwareTrigger();
      std::vector<std::vector<Frame>> got(sources.size());
      for (size_t k = 0; k < sources.size(); ++k) {
        auto f = sources[k]->Grab(o.grab_timeout_s);
        HOVS_REQUIRE(f.has_value() || (stop && stop->load()), "capture", "camera ", names[k],
                     " delivered no frame within ", o.grab_timeout_s, " s (timeout)");
        if (!f) break;
        if (f->complete) {
          // Every frame of a camera has its first frame's size and pixel format (a dataset's unit has one).
          Frame& first = first_frame[k];
          if (first.width == 0) first.width = f->width, first.height = f->height, first.pixel_format = f->pixel_format;
          HOVS_REQUIRE(f->width == first.width && f->height == first.height && f->pixel_format == first.pixel_format,
                       "capture", "camera ", names[k], "'s frame ", f->frame_id, " is ", f->width, " x ", f->height,
                       " ", f->pixel_format, " but its first was ", first.width, " x ", first.height, " ",
                       first.pixel_format);
        }
        if (!f->complete) {
          ++r.incomplete;
          std::lock_guard<std::mutex> lock(mu);
          m["incomplete_frames"].push_back(
              {{"unit", names[k]}, {"frame_id", f->frame_id}, {"status", f->status}, {"device_ns", f->device_ns}});
          continue;
        }
        got[k].push_back(std::move(*f));
      }
      snapshot_stats();
      std::vector<std::vector<Frame>> sets;
      if (sources.size() == 1) {
        for (auto& f : got[0]) sets.push_back({std::move(f)});
      } else {
        for (int k = 0; k < 2; ++k)
          for (auto& f : got[k])
            for (auto& pr : pairer.Add(k, std::move(f))) sets.push_back({std::move(pr.first), std::move(pr.second)});
        std::lock_guard<std::mutex> lock(mu);
        r.unpaired = pairer.dropped;
      }
      for (auto& set : sets) {
        if (queued >= o.frames) break;
        Pending p{queued, {}, {}};
        for (size_t k = 0; k < set.size(); ++k) {
          char rel[96];
          std::snprintf(rel, sizeof rel, "images/%s_%04d.%s", names[k].c_str(), queued, o.image_format.c_str());
          p.views.push_back(view_json(k, set[k], rel));
        }
        p.frames = std::move(set);
        std::unique_lock<std::mutex> lock(mu);
        not_full.wait(lock, [&] { return static_cast<int>(queue.size()) < o.write_queue || writer_error; });
        if (writer_error) break;
        queue.push_back(std::move(p));
        last_progress = std::chrono::steady_clock::now();
        r.max_queue_depth = std::max(r.max_queue_depth, static_cast<int>(queue.size()));
        ++queued;
        lock.unlock();
        not_empty.notify_one();
      }
    }
    finish_writer();
    if (writer_error) std::rethrow_exception(writer_error);
  } catch (...) {
    finish_writer();
    for (auto* s : sources) s->Stop();
    std::lock_guard<std::mutex> lock(mu);
    std::string why;
    try {
      throw;
    } catch (const std::exception& e) { why = std::string(": ") + e.what(); } catch (...) {
    }
    m["status"] = "stopped by an error after " + std::to_string(r.written) + " frames" + why;
    try {
      write_manifest_locked();
    } catch (...) {}
    throw;
  }
  if (o.progress) std::fprintf(stderr, "\n");
  for (auto* s : sources) s->Stop();
  snapshot_stats();
  std::lock_guard<std::mutex> lock(mu);
  if (r.written == 0 && !r.interrupted) {
    // The time limit came before any complete frame: a failed capture, said so in the manifest too.
    const std::string why = "no complete frame within the " + std::to_string(o.max_seconds) + " s limit (" +
                            std::to_string(r.incomplete) + " incomplete frames)";
    m["status"] = "stopped by an error after 0 frames: " + why;
    write_manifest_locked();
    throw Error("capture", why);
  }
  m["status"] = r.interrupted ? "interrupted after " + std::to_string(r.written) + " frames" : "complete";
  write_manifest_locked();
  return r;
}

}  // namespace hovs::hw
