// A GigE Vision camera simulator in process (Aravis' ArvGvFakeCamera) that serves given frames: the renderer's
// catadioptric images cross the real GigE Vision protocol (GVCP control, GVSP stream over UDP) before hovs
// captures them. Used by the tests and by `hovs capture --simulate`.
//
// Each served frame is frames[k % N] with its first 8 bytes replaced by k (little-endian), so a receiver can
// tell exactly which frame it got and check every byte (ServedFrame). The sensor size is set to the frames' size.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace hovs::hw {

struct FakeFrame {
  int width = 0, height = 0;
  std::vector<uint8_t> data;  // Mono8 or BayerRG8: width * height bytes
};

// The largest share of GVSP packets the simulator drops on purpose (beyond half, Aravis' resend cannot keep up).
inline constexpr double kMaxLostPacketRatio = 0.49;

class FakeGigECamera {
 public:
  // interface: an address like "127.0.0.1" or an interface name. lost_packet_ratio: GVSP packets the simulator
  // drops on purpose (0.01 = 1 %). Throws hovs::Error if the simulator cannot bind.
  FakeGigECamera(const std::string& interface, const std::string& serial, std::vector<FakeFrame> frames,
                 double lost_packet_ratio = 0);
  ~FakeGigECamera();
  FakeGigECamera(const FakeGigECamera&) = delete;
  FakeGigECamera& operator=(const FakeGigECamera&) = delete;

  // The bytes of the k-th served frame (what the receiver must get, byte for byte).
  std::vector<uint8_t> ServedFrame(uint64_t k) const;
  // The stamp of a received frame (its first 8 bytes).
  static uint64_t Stamp(const std::vector<uint8_t>& data);
  uint64_t served() const { return served_.load(); }

 private:
  static void Fill(void* buffer, void* self, uint32_t exposure_us, uint32_t gain, uint32_t pixel_format);
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<FakeFrame> frames_;
  std::atomic<uint64_t> served_{0};
};

}  // namespace hovs::hw
