#include "stream/subscriber.h"

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>

#include <chrono>
#include <thread>

#include "core/error.h"
#include "ros2_types.h"

namespace hovs::stream {

Subscriber::Subscriber(const DdsOptions& options, const std::string& ros_topic, MessageType type, int depth)
    : participant_(std::make_unique<Participant>(options)), ros_topic_(ros_topic) {
  HOVS_REQUIRE(depth >= 1, ros_topic, "the reader's depth must be at least 1");
  const dds_topic_descriptor_t* desc = type == MessageType::kImage        ? &sensor_msgs_msg_dds__Image__desc
                                       : type == MessageType::kCameraInfo ? &sensor_msgs_msg_dds__CameraInfo__desc
                                                                          : &sensor_msgs_msg_dds__PointCloud2__desc;
  topic_ = dds_create_topic(participant_->handle(), desc, DdsTopic(ros_topic).c_str(), nullptr, nullptr);
  HOVS_REQUIRE(topic_ > 0, ros_topic, "Cyclone DDS refused the topic: ", dds_strretcode(topic_));
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth);
  reader_ = dds_create_reader(participant_->handle(), topic_, q, nullptr);
  dds_delete_qos(q);
  HOVS_REQUIRE(reader_ > 0, ros_topic, "Cyclone DDS refused the reader: ", dds_strretcode(reader_));
}

Subscriber::~Subscriber() = default;  // the participant deletes its topic and reader

int Subscriber::Matched() const {
  dds_subscription_matched_status_t st;
  return dds_get_subscription_matched_status(reader_, &st) == DDS_RETCODE_OK ? static_cast<int>(st.current_count) : 0;
}

std::optional<std::vector<uint8_t>> Subscriber::Take(double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                          std::chrono::duration<double>(timeout_s));
  for (;;) {
    ddsi_serdata* sd = nullptr;
    dds_sample_info_t info;
    const dds_return_t n = dds_takecdr(reader_, &sd, 1, &info, DDS_ANY_STATE);
    HOVS_REQUIRE(n >= 0, ros_topic_, "Cyclone DDS could not take a message: ", dds_strretcode(n));
    if (n == 1) {
      std::optional<std::vector<uint8_t>> out;
      if (info.valid_data) {
        out.emplace(ddsi_serdata_size(sd));
        ddsi_serdata_to_ser(sd, 0, out->size(), out->data());
      }
      ddsi_serdata_unref(sd);
      if (out) return out;
      continue;  // a state change, not data
    }
    if (std::chrono::steady_clock::now() > end) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

}  // namespace hovs::stream
