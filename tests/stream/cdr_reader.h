// The ROS 2 messages hovs publishes, decoded from their CDR bytes by a reader written from ROS 2's .msg files
// (builtin_interfaces/Time, std_msgs/Header, sensor_msgs/Image, PointField, PointCloud2, RegionOfInterest,
// CameraInfo) and the plain-CDR rules ROS 2 uses (XCDR1: each primitive aligned to its size from the start of
// the body, strings as a uint32 length counting the NUL, sequences as a uint32 count). Independent of the IDL
// hovs compiles, so that a field out of place or of another width shows up as a wrong value or a wrong length.
#pragma once

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace hovs::test {

class CdrReader {
 public:
  explicit CdrReader(const std::vector<uint8_t>& bytes) : b_(bytes) {
    if (b_.size() < 4 || b_[0] != 0x00 || b_[1] != 0x01) throw std::runtime_error("not little-endian plain CDR");
    pos_ = 4;
  }
  template <class T>
  T Get() {
    Align(sizeof(T));
    Need(sizeof(T));
    T v;
    std::memcpy(&v, &b_[pos_], sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string String() {
    const uint32_t n = Get<uint32_t>();
    if (n == 0) throw std::runtime_error("a string without its NUL");
    Need(n);
    if (b_[pos_ + n - 1] != 0) throw std::runtime_error("a string not ended by NUL");
    std::string s(reinterpret_cast<const char*>(&b_[pos_]), n - 1);
    pos_ += n;
    return s;
  }
  std::vector<uint8_t> Octets() {
    const uint32_t n = Get<uint32_t>();
    Need(n);
    std::vector<uint8_t> v(b_.begin() + static_cast<long>(pos_), b_.begin() + static_cast<long>(pos_ + n));
    pos_ += n;
    return v;
  }
  // Bytes left after the last field, beyond the padding to a multiple of 4 that serialisers may add.
  size_t Trailing() const {
    const size_t left = b_.size() - pos_;
    return left < 4 ? 0 : left;
  }

 private:
  void Align(size_t a) {
    while ((pos_ - 4) % a) ++pos_;
  }
  void Need(size_t n) const {
    if (pos_ + n > b_.size()) throw std::runtime_error("message ends early");
  }
  const std::vector<uint8_t>& b_;
  size_t pos_ = 0;
};

struct RosHeader {
  int32_t sec = 0;
  uint32_t nanosec = 0;
  std::string frame_id;
};
inline RosHeader ReadHeader(CdrReader* r) {
  RosHeader h;
  h.sec = r->Get<int32_t>();
  h.nanosec = r->Get<uint32_t>();
  h.frame_id = r->String();
  return h;
}

struct RosImage {
  RosHeader header;
  uint32_t height = 0, width = 0, step = 0;
  std::string encoding;
  uint8_t is_bigendian = 0;
  std::vector<uint8_t> data;
  size_t trailing = 0;
};
inline RosImage DecodeImage(const std::vector<uint8_t>& bytes) {
  CdrReader r(bytes);
  RosImage m;
  m.header = ReadHeader(&r);
  m.height = r.Get<uint32_t>();
  m.width = r.Get<uint32_t>();
  m.encoding = r.String();
  m.is_bigendian = r.Get<uint8_t>();
  m.step = r.Get<uint32_t>();
  m.data = r.Octets();
  m.trailing = r.Trailing();
  return m;
}

struct RosCameraInfo {
  RosHeader header;
  uint32_t height = 0, width = 0, binning_x = 0, binning_y = 0;
  std::string distortion_model;
  std::vector<double> d;
  double k[9], r[9], p[12];
  uint32_t roi[4];
  bool do_rectify = true;
  size_t trailing = 0;
};
inline RosCameraInfo DecodeCameraInfo(const std::vector<uint8_t>& bytes) {
  CdrReader r(bytes);
  RosCameraInfo m;
  m.header = ReadHeader(&r);
  m.height = r.Get<uint32_t>();
  m.width = r.Get<uint32_t>();
  m.distortion_model = r.String();
  const uint32_t nd = r.Get<uint32_t>();
  for (uint32_t i = 0; i < nd; ++i) m.d.push_back(r.Get<double>());
  for (double& v : m.k) v = r.Get<double>();
  for (double& v : m.r) v = r.Get<double>();
  for (double& v : m.p) v = r.Get<double>();
  m.binning_x = r.Get<uint32_t>();
  m.binning_y = r.Get<uint32_t>();
  for (uint32_t& v : m.roi) v = r.Get<uint32_t>();
  m.do_rectify = r.Get<uint8_t>() != 0;
  m.trailing = r.Trailing();
  return m;
}

struct RosPointField {
  std::string name;
  uint32_t offset = 0, count = 0;
  uint8_t datatype = 0;
};
struct RosPointCloud2 {
  RosHeader header;
  uint32_t height = 0, width = 0, point_step = 0, row_step = 0;
  std::vector<RosPointField> fields;
  bool is_bigendian = true, is_dense = false;
  std::vector<uint8_t> data;
  size_t trailing = 0;
};
inline RosPointCloud2 DecodePointCloud2(const std::vector<uint8_t>& bytes) {
  CdrReader r(bytes);
  RosPointCloud2 m;
  m.header = ReadHeader(&r);
  m.height = r.Get<uint32_t>();
  m.width = r.Get<uint32_t>();
  const uint32_t nf = r.Get<uint32_t>();
  for (uint32_t i = 0; i < nf; ++i) {
    RosPointField f;
    f.name = r.String();
    f.offset = r.Get<uint32_t>();
    f.datatype = r.Get<uint8_t>();
    f.count = r.Get<uint32_t>();
    m.fields.push_back(f);
  }
  m.is_bigendian = r.Get<uint8_t>() != 0;
  m.point_step = r.Get<uint32_t>();
  m.row_step = r.Get<uint32_t>();
  m.data = r.Octets();
  m.is_dense = r.Get<uint8_t>() != 0;
  m.trailing = r.Trailing();
  return m;
}

}  // namespace hovs::test
