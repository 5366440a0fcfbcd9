#include "stream/publisher.h"

#include <dds/dds.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "core/error.h"
#include "ros2_types.h"

namespace hovs::stream {
namespace {

using Clock = std::chrono::steady_clock;

dds_qos_t* WriterQos(const DdsOptions& o) {
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, static_cast<dds_duration_t>(o.max_blocking_s * 1e9));
  dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
  // Keep-last deep enough (16 by default) that a sample whose fragments the reader's socket dropped is still
  // there to resend when its retransmission request arrives, a few frames later at worst.
  if (o.history == 0)
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
  else
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, o.history);
  return q;
}

void FillHeader(std_msgs_msg_dds__Header_* h, uint64_t stamp_ns, const std::string& frame_id) {
  h->stamp.sec = static_cast<int32_t>(stamp_ns / 1000000000ull);
  h->stamp.nanosec = static_cast<uint32_t>(stamp_ns % 1000000000ull);
  h->frame_id = const_cast<char*>(frame_id.c_str());
}

template <class T>
void Borrow(T* seq, const void* data, size_t n) {  // a sequence pointing at caller-owned data (dds_write copies)
  seq->_maximum = seq->_length = static_cast<uint32_t>(n);
  seq->_buffer = static_cast<decltype(seq->_buffer)>(const_cast<void*>(data));
  seq->_release = false;
}

}  // namespace

struct Publisher::Writers {
  struct Entry {
    std::string ros, frame_id;
    MessageType type;
    dds_entity_t topic = 0, writer = 0;
  };
  std::vector<Entry> image, info;  // info[k].writer == 0: no CameraInfo for image k
  Entry cloud;
  std::vector<Entry*> All() {
    std::vector<Entry*> out;
    for (auto& e : image) out.push_back(&e);
    for (auto& e : info)
      if (e.writer) out.push_back(&e);
    if (cloud.writer) out.push_back(&cloud);
    return out;
  }
};

std::optional<CameraInfo> CameraInfoOfView(const unwrap::ViewSpec& spec) {
  if (spec.type != ViewProjection::kPerspective) return std::nullopt;
  const VirtualView<double> v = spec.View();
  CameraInfo c;
  c.width = v.width, c.height = v.height;
  c.k = {v.camera.fx, 0, v.camera.cx, 0, v.camera.fy, v.camera.cy, 0, 0, 1};
  c.r = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  c.p = {v.camera.fx, 0, v.camera.cx, 0, 0, v.camera.fy, v.camera.cy, 0, 0, 0, 1, 0};
  return c;
}

PublisherTopics TopicsOfViews(const std::vector<unwrap::ViewSpec>& views, const std::string& prefix, bool cloud) {
  PublisherTopics t;
  t.prefix = prefix, t.cloud = cloud;
  for (const auto& v : views) t.images.push_back({v.name, CameraInfoOfView(v), ""});
  return t;
}

nlohmann::json PublishStats::ToJson() const {
  return {{"offered", offered},
          {"published", published},
          {"dropped", dropped},
          {"incomplete", incomplete},
          {"write_timeouts", write_timeouts},
          {"write_errors", write_errors},
          {"write_ms_mean", published + incomplete > 0 ? write_ms_total / double(published + incomplete) : 0.0},
          {"write_ms_max", write_ms_max}};
}

Publisher::Publisher(const DdsOptions& options, const PublisherTopics& topics)
    : topics_(topics), participant_(std::make_unique<Participant>(options)), writers_(std::make_unique<Writers>()) {
  HOVS_REQUIRE(!topics_.images.empty() || topics_.cloud, "DDS publisher", "nothing to publish");
  CheckRosNamespace(topics_.prefix, "DDS publisher (topic prefix)");
  dds_qos_t* qos = WriterQos(options);
  const dds_entity_t pp = participant_->handle();
  auto make = [&](Writers::Entry* e, const std::string& ros, const std::string& frame, MessageType type) {
    const dds_topic_descriptor_t* desc = type == MessageType::kImage        ? &sensor_msgs_msg_dds__Image__desc
                                         : type == MessageType::kCameraInfo ? &sensor_msgs_msg_dds__CameraInfo__desc
                                                                            : &sensor_msgs_msg_dds__PointCloud2__desc;
    e->ros = ros, e->frame_id = frame, e->type = type;
    e->topic = dds_create_topic(pp, desc, DdsTopic(ros).c_str(), nullptr, nullptr);
    HOVS_REQUIRE(e->topic > 0, ros, "Cyclone DDS refused the topic: ", dds_strretcode(e->topic));
    e->writer = dds_create_writer(pp, e->topic, qos, nullptr);
    HOVS_REQUIRE(e->writer > 0, ros, "Cyclone DDS refused the writer: ", dds_strretcode(e->writer));
  };
  try {
    std::vector<std::string> seen;
    for (const auto& im : topics_.images) {
      HOVS_REQUIRE(im.encoding.empty() || im.encoding == "32FC1", im.name, "unknown encoding '", im.encoding, "'");
      const std::string base = RosTopic(topics_.prefix, {im.name});
      for (const auto& s : seen)
        HOVS_REQUIRE(s != base, "DDS publisher", "two views map to the topic ", base, " (view names differ only in ",
                     "characters ROS does not allow)");
      seen.push_back(base);
      const std::string frame = RosTopic(topics_.prefix, {im.name}).substr(1);
      std::string frame_id = frame;
      for (char& c : frame_id)
        if (c == '/') c = '_';
      writers_->image.emplace_back();
      make(&writers_->image.back(), base + "/image_raw", frame_id, MessageType::kImage);
      writers_->info.emplace_back();
      if (im.info) make(&writers_->info.back(), base + "/camera_info", frame_id, MessageType::kCameraInfo);
    }
    if (topics_.cloud) {
      std::string frame_id = RosTopic(topics_.prefix, {"points"}).substr(1);
      for (char& c : frame_id)
        if (c == '/') c = '_';
      make(&writers_->cloud, RosTopic(topics_.prefix, {"points"}), frame_id, MessageType::kPointCloud2);
    }
  } catch (...) {
    dds_delete_qos(qos);
    throw;
  }
  dds_delete_qos(qos);
  thread_ = std::thread([this] { Run(); });
}

Publisher::~Publisher() {
  Flush(2.0);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void Publisher::Offer(Bundle* bundle, bool wait) {
  HOVS_REQUIRE(bundle->images.size() == topics_.images.size(), "DDS publisher", "a bundle of ", bundle->images.size(),
               " images for ", topics_.images.size(), " image topics");
  for (size_t k = 0; k < bundle->images.size(); ++k) {
    const auto& info = topics_.images[k].info;
    const auto& im = bundle->images[k];
    const std::string& enc = topics_.images[k].encoding;
    HOVS_REQUIRE(enc.empty() ? (im.channels == 1 || im.channels == 3) : (enc == "32FC1" && im.channels == 4),
                 topics_.images[k].name, "an image of ", im.channels, " bytes per pixel for encoding ",
                 enc.empty() ? "mono8 or rgb8" : enc);
    HOVS_REQUIRE(im.data.size() == size_t(im.width) * im.height * im.channels, topics_.images[k].name, "an image of ",
                 im.width, " x ", im.height, " x ", im.channels, " holds ", im.data.size(), " bytes");
    HOVS_REQUIRE(!info || (info->width == im.width && info->height == im.height), topics_.images[k].name, "image ",
                 im.width, " x ", im.height, " but its camera is ", info->width, " x ", info->height);
  }
  const PointCloud& pc = bundle->cloud;
  HOVS_REQUIRE(pc.width == 0 || (pc.width > 0 && pc.height > 0 && pc.xyz.size() == 3 * size_t(pc.width) * pc.height &&
                                 (pc.rgb.empty() || pc.rgb.size() == pc.xyz.size())),
               "DDS publisher", "a point cloud of ", pc.width, " x ", pc.height, " points holds ", pc.xyz.size(),
               " coordinates and ", pc.rgb.size(), " colour bytes");
  std::unique_lock<std::mutex> lock(mutex_);
  ++stats_.offered;
  if (pending_) {
    if (wait) {
      cv_.wait(lock, [&] { return !pending_; });
    } else {
      ++stats_.dropped;  // the waiting bundle is replaced by this newer one
    }
  }
  std::swap(slot_, *bundle);
  pending_ = true;
  cv_.notify_all();
}

bool Publisher::Flush(double timeout_s) {
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!cv_.wait_until(lock, end, [&] { return !pending_ && !writing_; })) return false;
  }
  // Written is not delivered: a sample a reader has not acknowledged yet (it lagged, or a fragment needs
  // resending) is lost if the process ends now.
  bool acked = true;
  for (auto* e : writers_->All()) {
    const double left = std::chrono::duration<double>(end - Clock::now()).count();
    const dds_duration_t t = static_cast<dds_duration_t>(std::max(0.0, left) * 1e9);
    acked = dds_wait_for_acks(e->writer, t) == DDS_RETCODE_OK && acked;
  }
  return acked;
}

bool Publisher::WaitForSubscribers(int count, double timeout_s, bool camera_info) {
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
  std::vector<Writers::Entry*> wanted;  // the images and the cloud; a CameraInfo only when asked
  for (auto& e : writers_->image) wanted.push_back(&e);
  if (writers_->cloud.writer) wanted.push_back(&writers_->cloud);
  if (camera_info)
    for (auto& e : writers_->info)
      if (e.writer) wanted.push_back(&e);
  for (;;) {
    bool all = true;
    for (auto* e : wanted) {
      dds_publication_matched_status_t st;
      if (dds_get_publication_matched_status(e->writer, &st) != DDS_RETCODE_OK ||
          static_cast<int>(st.current_count) < count)
        all = false;
    }
    if (all) return true;
    if (Clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

PublishStats Publisher::Stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

std::vector<std::string> Publisher::Topics() const {
  std::vector<std::string> out;
  for (auto* e : writers_->All()) out.push_back(e->ros + " (" + RosTypeName(e->type) + ")");
  return out;
}

void Publisher::Run() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    cv_.wait(lock, [&] { return pending_ || stop_; });
    if (!pending_) return;  // stopping with nothing left
    std::swap(slot_, working_);
    pending_ = false, writing_ = true;
    cv_.notify_all();
    lock.unlock();
    const auto t0 = Clock::now();
    Write(working_);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    lock.lock();
    stats_.write_ms_total += ms;
    stats_.write_ms_max = std::max(stats_.write_ms_max, ms);
    writing_ = false;
    cv_.notify_all();
  }
}

void Publisher::Write(const Bundle& b) {
  uint64_t timeouts = 0, errors = 0;
  auto count = [&](dds_return_t rc) {
    if (rc == DDS_RETCODE_TIMEOUT)
      ++timeouts;
    else if (rc != DDS_RETCODE_OK)
      ++errors;
  };
  for (size_t k = 0; k < b.images.size(); ++k) {
    const auto& im = b.images[k];
    const auto& e = writers_->image[k];
    sensor_msgs_msg_dds__Image_ m;
    std::memset(&m, 0, sizeof m);
    FillHeader(&m.header, b.stamp_ns, e.frame_id);
    m.height = static_cast<uint32_t>(im.height), m.width = static_cast<uint32_t>(im.width);
    const std::string& enc = topics_.images[k].encoding;
    m.encoding = const_cast<char*>(!enc.empty() ? enc.c_str() : im.channels == 3 ? "rgb8" : "mono8");
    m.is_bigendian = 0;
    m.step = static_cast<uint32_t>(im.width * im.channels);
    Borrow(&m.data, im.data.data(), im.data.size());
    count(dds_write(e.writer, &m));
    const auto& info = topics_.images[k].info;
    if (!info) continue;
    const auto& ie = writers_->info[k];
    sensor_msgs_msg_dds__CameraInfo_ c;
    std::memset(&c, 0, sizeof c);
    FillHeader(&c.header, b.stamp_ns, ie.frame_id);
    c.height = static_cast<uint32_t>(info->height), c.width = static_cast<uint32_t>(info->width);
    c.distortion_model = const_cast<char*>(info->distortion_model.c_str());
    Borrow(&c.d, info->d.data(), info->d.size());
    std::memcpy(c.k, info->k.data(), sizeof c.k);
    std::memcpy(c.r, info->r.data(), sizeof c.r);
    std::memcpy(c.p, info->p.data(), sizeof c.p);
    count(dds_write(ie.writer, &c));
  }
  if (topics_.cloud && b.cloud.width > 0) {
    const PointCloud& pc = b.cloud;
    const size_t n = size_t(pc.width) * pc.height;
    const bool rgb = pc.rgb.size() == 3 * n;
    const uint32_t step = rgb ? 16 : 12;
    std::vector<uint8_t> data(n * step);
    bool dense = true;
    for (size_t i = 0; i < n; ++i) {
      std::memcpy(&data[i * step], &pc.xyz[3 * i], 12);
      dense =
          dense && std::isfinite(pc.xyz[3 * i]) && std::isfinite(pc.xyz[3 * i + 1]) && std::isfinite(pc.xyz[3 * i + 2]);
      if (rgb) {
        const uint8_t packed[4] = {pc.rgb[3 * i + 2], pc.rgb[3 * i + 1], pc.rgb[3 * i], 0};  // b, g, r: PCL's order
        std::memcpy(&data[i * step + 12], packed, 4);
      }
    }
    sensor_msgs_msg_dds__PointField_ fields[4];
    const char* names[4] = {"x", "y", "z", "rgb"};
    for (int f = 0; f < 4; ++f) {
      fields[f].name = const_cast<char*>(names[f]);
      fields[f].offset = static_cast<uint32_t>(4 * f);
      fields[f].datatype = 7;  // FLOAT32
      fields[f].count = 1;
    }
    sensor_msgs_msg_dds__PointCloud2_ m;
    std::memset(&m, 0, sizeof m);
    FillHeader(&m.header, b.stamp_ns, writers_->cloud.frame_id);
    m.height = static_cast<uint32_t>(pc.height), m.width = static_cast<uint32_t>(pc.width);
    Borrow(&m.fields, fields, rgb ? 4 : 3);
    m.is_bigendian = false;
    m.point_step = step;
    m.row_step = step * static_cast<uint32_t>(pc.width);
    Borrow(&m.data, data.data(), data.size());
    m.is_dense = dense;
    count(dds_write(writers_->cloud.writer, &m));
  }
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.write_timeouts += timeouts, stats_.write_errors += errors;
  ++(timeouts + errors == 0 ? stats_.published : stats_.incomplete);
}

}  // namespace hovs::stream
