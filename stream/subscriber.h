// A DDS reader of hovs' topics that hands over each message as it travelled: its CDR bytes (with the 4-byte
// encapsulation header), for tests and tools that check what a ROS 2 node receives.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "stream/dds.h"

namespace hovs::stream {

class Subscriber {
 public:
  // A reliable, volatile reader of the ROS 2 topic `ros_topic` (travelling as rt/...) keeping the last `depth`
  // messages it has not handed over. Throws hovs::Error naming the topic.
  Subscriber(const DdsOptions& options, const std::string& ros_topic, MessageType type, int depth = 64);
  ~Subscriber();
  Subscriber(const Subscriber&) = delete;
  Subscriber& operator=(const Subscriber&) = delete;

  int Matched() const;  // writers matched now
  // The next message's serialised bytes, waiting up to timeout_s; nullopt when none arrived.
  std::optional<std::vector<uint8_t>> Take(double timeout_s);

 private:
  std::unique_ptr<Participant> participant_;
  int32_t topic_ = 0, reader_ = 0;
  std::string ros_topic_;
};

}  // namespace hovs::stream
