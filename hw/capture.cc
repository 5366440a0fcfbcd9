#include "hw/capture.h"

#include <chrono>
#include <cstdio>

#include "core/error.h"
#include "core/io.h"
#include "raytrace/render.h"

namespace hovs::hw {
namespace fs = std::filesystem;

void CaptureOptions::Check(size_t sources, const std::string& where) const {
  HOVS_REQUIRE(sources == 1 || sources == 2, where, "capture takes one or two cameras (got ", sources, ")");
  HOVS_REQUIRE(frames >= 1, where, "frames must be at least 1 (got ", frames, ")");
  HOVS_REQUIRE(max_seconds >= 0 && grab_timeout_s > 0, where, "durations must be positive");
  HOVS_REQUIRE(unit_names.empty() || unit_names.size() == sources, where, "one unit name per camera");
}

namespace {

// An 8-bit one-channel PNG (Mono8 or a raw BayerRG8 mosaic), or 16-bit for Mono16; written atomically.
void WriteFrameImage(const fs::path& path, const Frame& f) {
  std::vector<float> v(size_t(f.width) * f.height);
  if (f.pixel_format == "Mono16") {
    for (size_t k = 0; k < v.size(); ++k) v[k] = float(f.data[2 * k] | (f.data[2 * k + 1] << 8)) / 65535.f;
  } else {
    for (size_t k = 0; k < v.size(); ++k) v[k] = f.data[k] / 255.f;
  }
  const fs::path tmp = path.parent_path() / ("." + path.filename().string() + ".tmp.png");
  raytrace::WriteImage(tmp, f.width, f.height, 1, v, f.pixel_format == "Mono16" ? 16 : 8);
  std::error_code ec;
  fs::rename(tmp, path, ec);
  HOVS_REQUIRE(!ec, path.string(), "cannot rename the written image into place: ", ec.message());
}

}  // namespace

CaptureResult CaptureDataset(const std::vector<CameraSource*>& sources, const CaptureOptions& o, const fs::path& out,
                             const nlohmann::json& versions, const std::atomic<bool>* stop) {
  o.Check(sources.size(), "capture");
  fs::create_directories(out / "images");
  std::vector<std::string> names = o.unit_names;
  for (size_t k = names.size(); k < sources.size(); ++k) names.push_back("unit" + std::to_string(k));
  CaptureResult r;
  nlohmann::json units = nlohmann::json::array();
  for (size_t k = 0; k < sources.size(); ++k) units.push_back({{"name", names[k]}, {"camera", sources[k]->Info()}});
  nlohmann::json& m = r.manifest;
  m = {{"format", "hovs-dataset"}, {"version", 1}, {"kind", "capture"}, {"name", "capture"},
       {"generator", "hovs capture"}, {"versions", versions}, {"units", units}, {"frames", nlohmann::json::array()},
       {"incomplete_frames", nlohmann::json::array()}, {"status", "capturing"},
       {"note", "real capture: no ground truth; images are raw sensor data (Mono8, BayerRG8 mosaic or Mono16)"}};
  auto write_manifest = [&]() {
    nlohmann::json stats = nlohmann::json::object();
    for (size_t k = 0; k < sources.size(); ++k) stats[names[k]] = sources[k]->Stats().ToJson();
    m["statistics"] = stats;
    m["unpaired_frames"] = r.unpaired;
    WriteFileAtomic(out / "dataset.json", m.dump(1) + "\n");
  };
  write_manifest();
  for (auto* s : sources) s->Start();
  const auto t0 = std::chrono::steady_clock::now();
  FramePairer pairer;
  pairer.tolerance_ns = o.pair_tolerance_ns;
  auto view_json = [&](size_t unit, const Frame& f, const std::string& rel) {
    const auto info = sources[unit]->Info();
    nlohmann::json v = {{"unit", names[unit]}, {"image", rel}, {"frame_id", f.frame_id}, {"device_ns", f.device_ns},
                        {"system_ns", f.system_ns}, {"pixel_format", f.pixel_format}, {"width", f.width},
                        {"height", f.height}, {"serial", info.value("serial", "")}};
    if (info.contains("exposure_us")) v["exposure_us"] = info["exposure_us"];
    if (info.contains("gain")) v["gain"] = info["gain"];
    return v;
  };
  try {
    while (r.written < o.frames) {
      if (stop && stop->load()) {
        r.interrupted = true;
        break;
      }
      if (o.max_seconds > 0 &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > o.max_seconds)
        break;
      if (o.software_trigger)
        for (auto* s : sources) s->SoftwareTrigger();
      std::vector<std::vector<Frame>> got(sources.size());
      for (size_t k = 0; k < sources.size(); ++k) {
        auto f = sources[k]->Grab(o.grab_timeout_s);
        HOVS_REQUIRE(f.has_value() || (stop && stop->load()), "capture",
                     "camera ", names[k], " delivered no frame within ", o.grab_timeout_s, " s (timeout)");
        if (!f) break;
        if (!f->complete) {
          ++r.incomplete;
          m["incomplete_frames"].push_back({{"unit", names[k]}, {"frame_id", f->frame_id}, {"status", f->status},
                                            {"device_ns", f->device_ns}});
          std::fprintf(stderr, "capture: %s frame %llu incomplete (%s), not written\n", names[k].c_str(),
                       static_cast<unsigned long long>(f->frame_id), f->status.c_str());
          continue;
        }
        got[k].push_back(std::move(*f));
      }
      std::vector<std::vector<Frame>> sets;
      if (sources.size() == 1) {
        for (auto& f : got[0]) sets.push_back({std::move(f)});
      } else {
        for (int k = 0; k < 2; ++k)
          for (auto& f : got[k])
            for (auto& pr : pairer.Add(k, std::move(f))) sets.push_back({std::move(pr.first), std::move(pr.second)});
        r.unpaired = pairer.dropped;
      }
      for (auto& set : sets) {
        if (r.written >= o.frames) break;
        nlohmann::json frame = {{"id", r.written}, {"views", nlohmann::json::array()}};
        for (size_t k = 0; k < set.size(); ++k) {
          char rel[96];
          std::snprintf(rel, sizeof rel, "images/%s_%04d.png", names[k].c_str(), r.written);
          WriteFrameImage(out / rel, set[k]);
          frame["views"].push_back(view_json(k, set[k], rel));
        }
        m["frames"].push_back(frame);
        ++r.written;
        write_manifest();
        if (o.progress) std::fprintf(stderr, "\rcapture: %d / %d frames", r.written, o.frames);
      }
    }
  } catch (...) {
    for (auto* s : sources) s->Stop();
    m["status"] = "stopped by an error after " + std::to_string(r.written) + " frames";
    try {
      write_manifest();
    } catch (...) {
    }
    throw;
  }
  if (o.progress) std::fprintf(stderr, "\n");
  for (auto* s : sources) s->Stop();
  m["status"] = r.interrupted ? "interrupted after " + std::to_string(r.written) + " frames" : "complete";
  write_manifest();
  return r;
}

}  // namespace hovs::hw
