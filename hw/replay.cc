// Replay of recorded frames, and pairing of two streams by timestamp.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "core/manifest.h"
#include "hw/camera_source.h"
#include "io/image_io.h"

namespace hovs::hw {
namespace {
namespace fs = std::filesystem;

struct ReplayItem {
  fs::path image;
  uint64_t device_ns = 0;
};

class Replay : public CameraSource {
 public:
  Replay(std::vector<ReplayItem> items, std::string source, std::string pixel_format, bool loop)
      : items_(std::move(items)), source_(std::move(source)), format_(std::move(pixel_format)), loop_(loop) {
    HOVS_REQUIRE(format_ == "Mono8" || format_ == "BayerRG8", source_, "replay supports Mono8 and BayerRG8 (got ",
                 format_, ")");
    HOVS_REQUIRE(!items_.empty(), source_, "no frames to replay");
  }
  nlohmann::json Info() const override {
    return {{"id", "replay:" + source_}, {"vendor", "hovs"},        {"model", "replay"},
            {"serial", source_},         {"pixel_format", format_}, {"frames", items_.size()}};
  }
  void Start() override { running_ = true; }
  void Stop() override { running_ = false; }
  void SoftwareTrigger() override {}
  StreamStats Stats() const override {
    StreamStats s;
    s.completed = next_;
    return s;
  }
  std::optional<Frame> Grab(double) override {
    HOVS_REQUIRE(running_, source_, "Grab before Start");
    if (next_ >= items_.size() && !loop_) return std::nullopt;
    const ReplayItem& it = items_[next_ % items_.size()];
    int w = 0, h = 0, c = 0;
    const io::PixelBuffer px = io::ReadImage(it.image, &w, &h, &c);
    // A camera's frames keep one size: a replay whose images change size is refused at the first that does.
    if (next_ == 0) first_width_ = w, first_height_ = h;
    HOVS_REQUIRE(w == first_width_ && h == first_height_, it.image.string(), "is ", w, " x ", h,
                 " but the replay's first frame is ", first_width_, " x ", first_height_,
                 " (a camera's frames keep one size)");
    Frame f;
    f.width = w, f.height = h, f.pixel_format = format_;
    f.frame_id = next_;
    f.device_ns = it.device_ns + (next_ / items_.size()) * items_.size() * 100'000'000ull;
    f.system_ns = static_cast<uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
    HOVS_REQUIRE(format_ == "Mono8" || c == 1, it.image.string(),
                 "BayerRG8 replay needs a one-channel mosaic (the file has ", c, " channels)");
    f.data.resize(size_t(w) * h);
    for (size_t k = 0; k < f.data.size(); ++k) {
      double v = px[k * c];
      if (c >= 3) v = 0.299 * px[k * c] + 0.587 * px[k * c + 1] + 0.114 * px[k * c + 2];
      f.data[k] = static_cast<uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255));
    }
    f.complete = true, f.status = "success";
    ++next_;
    return f;
  }

 private:
  std::vector<ReplayItem> items_;
  std::string source_, format_;
  bool loop_;
  bool running_ = false;
  size_t next_ = 0;
  int first_width_ = 0, first_height_ = 0;
};

}  // namespace

std::unique_ptr<CameraSource> OpenReplay(const fs::path& src, const std::string& unit, const std::string& pixel_format,
                                         bool loop) {
  std::vector<ReplayItem> items;
  if (fs::is_directory(src)) {
    for (const auto& f : ListImageFiles(src)) items.push_back({f, 0});
    for (size_t k = 0; k < items.size(); ++k) items[k].device_ns = k * 100'000'000ull;
  } else {
    const auto m = ReadJsonFile(src);
    HOVS_REQUIRE(m.is_object() && JsonText(m, "format") == "hovs-dataset", src.string(),
                 "neither a folder of images nor a hovs dataset manifest");
    CheckDatasetManifest(m, src.string());
    for (const auto& fr : m["frames"])
      for (const auto& v : fr["views"]) {
        if (!unit.empty() && v["unit"] != unit) continue;
        ReplayItem it{src.parent_path() / v["image"].get<std::string>(), 0};
        it.device_ns = v.contains("device_ns") ? v["device_ns"].get<uint64_t>() : items.size() * 100'000'000ull;
        items.push_back(it);
        if (unit.empty()) break;  // the first unit's view of each frame
      }
    if (!unit.empty() && items.empty()) {
      std::string names;
      for (const auto& u : m["units"]) names += (names.empty() ? "" : ", ") + u["name"].get<std::string>();
      throw Error(src.string(), "no frames of unit '" + unit + "' (its units: " + names + ")");
    }
  }
  return std::make_unique<Replay>(std::move(items), src.string(), pixel_format, loop);
}

std::vector<std::pair<Frame, Frame>> FramePairer::Add(int stream, Frame frame) {
  HOVS_REQUIRE(stream == 0 || stream == 1, "frame pairer", "stream must be 0 or 1");
  std::vector<std::pair<Frame, Frame>> out;
  auto& mine = pending_[stream];
  auto& other = pending_[1 - stream];
  // The closest frame of the other stream within the tolerance.
  size_t best = other.size();
  uint64_t best_dt = tolerance_ns + 1;
  for (size_t k = 0; k < other.size(); ++k) {
    const uint64_t dt = other[k].device_ns > frame.device_ns ? other[k].device_ns - frame.device_ns
                                                             : frame.device_ns - other[k].device_ns;
    if (dt < best_dt) best = k, best_dt = dt;
  }
  if (best == other.size()) {
    mine.push_back(std::move(frame));
    // Keep the queues short: a frame far older than the newest of the other stream will never pair.
    while (!mine.empty() && !other.empty() && mine.front().device_ns + 10 * tolerance_ns < other.back().device_ns)
      mine.erase(mine.begin()), ++dropped;
    return out;
  }
  // Frames of the other stream older than the match will not pair any more.
  dropped += best;
  Frame match = std::move(other[best]);
  other.erase(other.begin(), other.begin() + static_cast<long>(best) + 1);
  // Frames of this stream still waiting are older than this one: they lost their chance.
  dropped += mine.size();
  mine.clear();
  if (stream == 0)
    out.emplace_back(std::move(frame), std::move(match));
  else
    out.emplace_back(std::move(match), std::move(frame));
  return out;
}

}  // namespace hovs::hw
