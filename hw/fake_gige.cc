#include "hw/fake_gige.h"

#include <arv.h>

#include <cstring>

#include "core/error.h"

namespace hovs::hw {

struct FakeGigECamera::Impl {
  ArvGvFakeCamera* gv = nullptr;
};

FakeGigECamera::FakeGigECamera(const std::string& interface, const std::string& serial, std::vector<FakeFrame> frames,
                               double lost_packet_ratio)
    : impl_(std::make_unique<Impl>()), frames_(std::move(frames)) {
  HOVS_REQUIRE(!frames_.empty(), "camera simulator", "needs at least one frame");
  for (const auto& f : frames_)
    HOVS_REQUIRE(f.width == frames_[0].width && f.height == frames_[0].height &&
                     f.data.size() == size_t(f.width) * f.height && f.data.size() >= 8,
                 "camera simulator", "frames must share one size and hold width x height bytes");
  HOVS_REQUIRE(lost_packet_ratio >= 0 && lost_packet_ratio <= kMaxLostPacketRatio, "camera simulator",
               "lost packet ratio must lie in [0, ", kMaxLostPacketRatio, "]");
  impl_->gv = arv_gv_fake_camera_new(interface.c_str(), serial.c_str());
  if (!impl_->gv || !arv_gv_fake_camera_is_running(impl_->gv)) {
    if (impl_->gv) g_object_unref(impl_->gv);
    impl_->gv = nullptr;
    // Linux answers 127.0.0.2 on the loopback only once it is added there (the second unit of a stereo simulation).
    const std::string hint = interface.rfind("127.", 0) == 0 && interface != "127.0.0.1"
                                 ? "; add it with `ip addr add " + interface +
                                       "/8 dev lo` (as root), or run in a private "
                                       "network namespace as tests/hw/run_in_netns.sh does"
                                 : "";
    throw Error("camera simulator",
                "cannot serve on '" + interface + "' (address not configured or port in use)" + hint);
  }
  g_object_set(impl_->gv, "gvsp-lost-ratio", lost_packet_ratio, nullptr);
  ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(impl_->gv);
  const auto w = static_cast<guint32>(frames_[0].width), h = static_cast<guint32>(frames_[0].height);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_SENSOR_WIDTH, w);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_SENSOR_HEIGHT, h);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH, w);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT, h);
  arv_fake_camera_set_fill_pattern(
      fake,
      [](ArvBuffer* b, void* self, guint32 e, guint32 g, ArvPixelFormat f) {
        Fill(b, self, e, g, static_cast<uint32_t>(f));
      },
      this);
}

FakeGigECamera::~FakeGigECamera() {
  if (impl_ && impl_->gv) g_object_unref(impl_->gv);
}

std::vector<uint8_t> FakeGigECamera::ServedFrame(uint64_t k) const {
  std::vector<uint8_t> d = frames_[k % frames_.size()].data;
  for (int i = 0; i < 8; ++i) d[i] = static_cast<uint8_t>(k >> (8 * i));
  return d;
}

uint64_t FakeGigECamera::Stamp(const std::vector<uint8_t>& data) {
  uint64_t k = 0;
  for (int i = 0; i < 8 && i < static_cast<int>(data.size()); ++i) k |= uint64_t(data[i]) << (8 * i);
  return k;
}

void FakeGigECamera::Fill(void* buffer, void* self_ptr, uint32_t, uint32_t, uint32_t) {
  auto* self = static_cast<FakeGigECamera*>(self_ptr);
  auto* b = static_cast<ArvBuffer*>(buffer);
  // The received size is set after this callback: the image's own geometry gives the bytes to fill.
  auto* dst = static_cast<uint8_t*>(const_cast<void*>(arv_buffer_get_data(b, nullptr)));
  const size_t size =
      size_t(std::max(0, arv_buffer_get_image_width(b))) * size_t(std::max(0, arv_buffer_get_image_height(b)));
  const uint64_t k = self->served_.fetch_add(1);
  const FakeFrame& f = self->frames_[k % self->frames_.size()];
  const size_t n = std::min(size, f.data.size());
  std::memcpy(dst, f.data.data(), n);
  for (size_t i = 0; i < 8 && i < n; ++i) dst[i] = static_cast<uint8_t>(k >> (8 * i));
}

}  // namespace hovs::hw
