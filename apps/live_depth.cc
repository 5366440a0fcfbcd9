#include "apps/live_depth.h"

#include <cmath>
#include <cstdio>
#include <cstring>

#include "apps/commands.h"
#include "core/error.h"
#include "core/statistics.h"
#include "depth/stereo.h"

namespace hovs::apps {
namespace {

nlohmann::json Summary(const std::vector<double>& v) {
  if (v.empty()) return nlohmann::json();
  const SampleSummary s = Summarise(v);
  return {{"median_ms", s.median}, {"p95_ms", s.p95}, {"max_ms", s.max}, {"frames", s.count}};
}

}  // namespace

std::optional<depth::LiveDepthOptions> LiveDepthCliOptions::Resolve() const {
  if (!depth) {
    HOVS_REQUIRE(stereo.empty() && size == "2048x512" && disparities == 320, "--depth-size",
                 "the depth options need --depth");
    return std::nullopt;
  }
  depth::LiveDepthOptions o;
  int w = 0, h = 0, end = -1;
  HOVS_REQUIRE(std::sscanf(size.c_str(), "%dx%d%n", &w, &h, &end) == 2 && end == static_cast<int>(size.size()),
               "--depth-size", "expected WIDTHxHEIGHT (got '", size, "')");
  o.rectify.width = w, o.rectify.height = h;
  o.dense.num_disparities = disparities;
  o.Check("--depth-size/--depth-disparities");
  return o;
}

void AddLiveDepthOptions(CLI::App* sub, LiveDepthCliOptions* o) {
  sub->add_flag("--depth", o->depth,
                "frame pairs: dense depth and a point cloud on a thread of their own, at the rate the matcher keeps");
  sub->add_option("--depth-size", o->size, "rectified size WIDTHxHEIGHT of the depth views")->capture_default_str();
  AddBounded(sub, "--depth-disparities", &o->disparities, "disparity range, columns (multiple of 16)", 16, 4096);
  sub->add_option("--stereo", o->stereo, "stereo.json of hovs stereo-calibrate (default: the model's unit poses)");
}

LiveDepthOutput::LiveDepthOutput(const depth::StereoRig& rig, const depth::LiveDepthOptions& options,
                                 const std::optional<stream::DdsOptions>& dds, const std::string& prefix) {
  rect_width_ = options.rectify.width, rect_height_ = options.rectify.height;
  if (dds) {
    stream::PublisherTopics t;
    t.prefix = prefix, t.cloud = true;
    t.images.push_back({"depth", std::nullopt, "32FC1"});
    publisher_ = std::make_unique<stream::Publisher>(*dds, t);
  }
  worker_ = std::make_unique<depth::LiveDepth>(rig, options, [this](const depth::LiveDepthResult& r) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      last_xyz_ = r.xyz, last_rgb_ = r.rgb;
    }
    if (!publisher_) return;
    bundle_.stamp_ns = r.stamp_ns;
    bundle_.images.resize(1);
    unwrap::Image8& im = bundle_.images[0];
    im.width = rect_width_, im.height = rect_height_, im.channels = 4;
    im.data.resize(r.range.size() * 4);
    std::memcpy(im.data.data(), r.range.data(), im.data.size());
    bundle_.cloud.width = static_cast<int>(r.xyz.size() / 3), bundle_.cloud.height = 1;
    bundle_.cloud.xyz = r.xyz, bundle_.cloud.rgb = r.rgb;
    publisher_->Offer(&bundle_);
  });
}

hw::PairFramesSink LiveDepthOutput::Sink() {
  return [this](uint64_t stamp_ns, hw::Frame* left, hw::Frame* right) {
    const auto fmt = left->pixel_format == "BayerRG8" ? unwrap::PixelFormat::kBayerRggb8 : unwrap::PixelFormat::kGray8;
    worker_->Offer(&left->data, &right->data, left->width, left->height, fmt, stamp_ns);
  };
}

nlohmann::json LiveDepthOutput::Finish(const std::filesystem::path& out_dir, double run_seconds) {
  worker_->Drain(60);
  const depth::LiveDepthStats s = worker_->Stats();
  nlohmann::json j = {{"rectified_size", {rect_width_, rect_height_}},
                      {"baseline_m", worker_->rectification().baseline},
                      {"pairs_offered", s.offered},
                      {"depth_computed", s.computed},
                      {"pairs_skipped", s.skipped},
                      {"depth_fps", s.computed / std::max(run_seconds, 1e-9)},
                      {"latency",
                       {{"rectify", Summary(s.rectify_ms)},
                        {"match", Summary(s.match_ms)},
                        {"cloud", Summary(s.cloud_ms)},
                        {"total", Summary(s.total_ms)}}}};
  if (publisher_) {
    publisher_->Flush(5);
    j["dds"] = {{"topics", publisher_->Topics()}, {"frames", publisher_->Stats().ToJson()}};
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (!out_dir.empty() && !last_xyz_.empty()) {
    std::vector<depth::ColouredPoint> pts(last_xyz_.size() / 3);
    for (size_t i = 0; i < pts.size(); ++i) {
      pts[i].p = Vec3d(last_xyz_[3 * i], last_xyz_[3 * i + 1], last_xyz_[3 * i + 2]);
      pts[i].rgb = {last_rgb_[3 * i], last_rgb_[3 * i + 1], last_rgb_[3 * i + 2]};
    }
    depth::WritePly(out_dir / "points.ply", pts);
    j["last_cloud"] = {{"file", "points.ply"}, {"points", pts.size()}, {"frame", "the left unit's mirror frame"}};
  }
  return j;
}

}  // namespace hovs::apps
