// hovs' images, camera models and point clouds on DDS (Eclipse Cyclone DDS) with ROS 2's wire conventions, so
// that a ROS 2 node subscribes to hovs without hovs depending on ROS:
//   - a ROS topic /P/N travels as the DDS topic rt/P/N (rmw's prefix for topics);
//   - the types are sensor_msgs/Image, sensor_msgs/CameraInfo and sensor_msgs/PointCloud2 as rosidl declares them
//     for DDS (stream/ros2_types.idl: sensor_msgs::msg::dds_::Image_, ...), in plain little-endian CDR;
//   - writers are reliable and volatile with a short history, which matches ROS 2's default and sensor-data QoS.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace hovs::stream {

// Where the participant talks. With neither `interface` nor `peers` Cyclone's own configuration applies
// (CYCLONEDDS_URI, else its defaults: multicast discovery on the first usable interface). With either, hovs
// configures the domain itself: that interface only, and with peers, unicast discovery to them and no multicast
// (the loopback has no multicast: interface "lo" with peer 127.0.0.1 is how one machine talks to itself).
struct DdsOptions {
  int domain = 0;                  // DDS domain id, 0 .. 232 (ROS_DOMAIN_ID)
  std::string interface;           // a network interface name ("lo", "eth0") or one of its addresses
  std::vector<std::string> peers;  // unicast discovery addresses
  double max_blocking_s = 0.1;     // how long a write may wait for a reliable reader's acknowledgements
  // Samples each writer keeps for retransmission. A reader that lags further behind loses the oldest (ROS 2's
  // KEEP_LAST behaviour: a live stream never waits for a slow reader). 0 keeps every sample until every reader
  // has acknowledged it (KEEP_ALL): nothing is lost, and a write blocks up to max_blocking_s while readers lag.
  int history = 16;
  void Check(const std::string& where) const;  // throws hovs::Error naming `where` (the option)
};

// The Cyclone configuration XML the options imply ("" when Cyclone's own applies).
std::string DdsConfigXml(const DdsOptions& options);

// A participant on the options' domain; the domain is created once per process and id, with its configuration
// (a second participant on the same id must ask for the same configuration). Throws hovs::Error naming the
// domain, interface or peer Cyclone refuses.
class Participant {
 public:
  explicit Participant(const DdsOptions& options);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;
  int32_t handle() const { return handle_; }
  const DdsOptions& options() const { return options_; }

 private:
  DdsOptions options_;
  int32_t handle_ = 0;
};

// ROS 2 graph names: a topic name from a prefix and parts ("hovs", "front", "image_raw" -> "/hovs/front/image_raw"),
// characters outside [A-Za-z0-9_] replaced by '_' and a leading digit prefixed with '_', as ROS requires.
std::string RosTopic(const std::string& prefix, const std::vector<std::string>& parts);
// A namespace the user gives (--topic-prefix) is used as given, never mangled: ROS 2's rules for names (tokens of
// letters, digits and '_' separated by '/', a leading '/' allowed; no token starting with a digit, no empty token,
// no trailing '/', no "__"), at most 200 characters so that every topic under it stays within rmw's limit.
// Throws hovs::Error(where) naming the rule broken.
void CheckRosNamespace(const std::string& ns, const std::string& where);
// The DDS topic a ROS 2 topic travels on: "/hovs/points" -> "rt/hovs/points".
std::string DdsTopic(const std::string& ros_topic);

enum class MessageType { kImage, kCameraInfo, kPointCloud2 };
std::string RosTypeName(MessageType type);  // "sensor_msgs/msg/Image", ...

}  // namespace hovs::stream
