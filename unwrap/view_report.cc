#include "unwrap/view_report.h"

#include <algorithm>
#include <cmath>

namespace hovs::unwrap {

nlohmann::json ViewJson(const ViewTable& vt) {
  const auto& v = vt.view;
  const auto& q = v.mirror_from_view;
  nlohmann::json j = {{"name", vt.spec.name},
                      {"type", ToString(v.projection)},
                      {"width", v.width},
                      {"height", v.height},
                      {"mirror_from_view", {{"qw", q.w()}, {"qx", q.x()}, {"qy", q.y()}, {"qz", q.z()}}},
                      {"valid_pixels", vt.valid_pixels},
                      {"tile_size", vt.tile},
                      {"tiles", {{"interp", vt.interp_tiles}, {"dense", vt.dense_tiles}, {"empty", vt.empty_tiles}}},
                      {"max_interp_error_px", vt.max_interp_error},
                      {"max_pyramid_level", vt.max_level}};
  if (v.projection == ViewProjection::kPerspective) {
    j["K"] = {{v.camera.fx, 0.0, v.camera.cx}, {0.0, v.camera.fy, v.camera.cy}, {0.0, 0.0, 1.0}};
    j["yaw_deg"] = vt.spec.yaw_deg, j["pitch_deg"] = vt.spec.pitch_deg, j["roll_deg"] = vt.spec.roll_deg;
    j["hfov_deg"] = vt.spec.hfov_deg;
  } else {
    j["elevation_deg"] = {vt.spec.elevation_min_deg, vt.spec.elevation_max_deg};
    j["azimuth_centre_deg"] = vt.spec.azimuth_centre_deg, j["azimuth_span_deg"] = vt.spec.azimuth_span_deg;
  }
  return j;
}

ViewPsnr CompareWithReference(const RemapTable& table, int view_index, const Image8& view,
                              const std::vector<uint8_t>& reference) {
  std::vector<float> mx, my;
  table.DecodeView(view_index, &mx, &my);
  double se = 0;
  int64_t n = 0;
  for (size_t k = 0; k < mx.size(); ++k) {
    if (mx[k] < 0) continue;
    for (int ch = 0; ch < 3; ++ch) se += std::pow(double(view.data[3 * k + ch]) - reference[3 * k + ch], 2);
    n += 3;
  }
  ViewPsnr r;
  r.psnr_db = n ? 10 * std::log10(255.0 * 255.0 * n / std::max(se, 1e-9)) : 0.0;
  r.valid_fraction = double(n / 3) / mx.size();
  return r;
}

}  // namespace hovs::unwrap
