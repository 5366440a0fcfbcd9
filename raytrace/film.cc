#include "raytrace/film.h"

#include <cmath>
#include <cstddef>
#include <limits>

#include "core/error.h"
#include "core/vector_clones.h"
#include "io/image_io.h"

namespace hovs::raytrace {

const char* const GroundTruth::kNames[GroundTruth::kChannels] = {"Z",   "P.X", "P.Y",  "P.Z", "N.X", "N.Y",
                                                                 "N.Z", "id",  "mask", "M.X", "M.Y", "M.Z"};

HOVS_VECTOR_CLONES
void SumSamples(int len, int samples, int row, float weight, const float* __restrict rgb, bool add,
                float* __restrict out) {
  // The last sample is added as the result is stored (a plain copy loop would become a library memcpy call).
  float sum[3 * RayBatch::kMax];
  const float* __restrict last = rgb + static_cast<ptrdiff_t>(samples - 1) * row;
  if (samples == 1) {
    if (add) {
      for (int j = 0; j < len; ++j) out[j] += weight * last[j];
    } else {
      for (int j = 0; j < len; ++j) out[j] = weight * last[j];
    }
    return;
  }
  for (int j = 0; j < len; ++j) sum[j] = weight * rgb[j];
  for (int smp = 1; smp < samples - 1; ++smp) {
    const float* __restrict r = rgb + static_cast<ptrdiff_t>(smp) * row;
    for (int j = 0; j < len; ++j) sum[j] += weight * r[j];
  }
  if (add) {
    for (int j = 0; j < len; ++j) out[j] += sum[j] + weight * last[j];
  } else {
    for (int j = 0; j < len; ++j) out[j] = sum[j] + weight * last[j];
  }
}

HOVS_VECTOR_CLONES
void GroundTruthLanes(int m, const unsigned char* __restrict valid, const int* __restrict from_mirror,
                      const unsigned char* __restrict hit, const int* __restrict object_id, const double* __restrict c,
                      const double* __restrict px, const double* __restrict py, const double* __restrict pz,
                      const double* __restrict nx, const double* __restrict ny, const double* __restrict nz,
                      const double* __restrict Mx, const double* __restrict My, const double* __restrict Mz,
                      float* __restrict out) {
  constexpr int K = RayBatch::kMax;
  const float inf = std::numeric_limits<float>::infinity();
  const double c0 = c[0], c1 = c[1], c2 = c[2];
  for (int k = 0; k < m; ++k) {
    const double x = px[k] - c0, y = py[k] - c1, z = pz[k] - c2, range = std::sqrt(x * x + y * y + z * z);
    const int live = valid[k] != 0 ? 1 : 0;
    const int met = live & (hit[k] != 0 ? 1 : 0);
    const int via = live & (from_mirror[k] >= 0 ? 1 : 0);
    const int seen = via & (object_id[k] != kCameraBodyId ? 1 : 0);
    out[k] = met ? static_cast<float>(range) : inf;
    out[K + k] = met ? static_cast<float>(px[k]) : 0.0f;
    out[2 * K + k] = met ? static_cast<float>(py[k]) : 0.0f;
    out[3 * K + k] = met ? static_cast<float>(pz[k]) : 0.0f;
    out[4 * K + k] = met ? static_cast<float>(nx[k]) : 0.0f;
    out[5 * K + k] = met ? static_cast<float>(ny[k]) : 0.0f;
    out[6 * K + k] = met ? static_cast<float>(nz[k]) : 0.0f;
    out[7 * K + k] = met ? static_cast<float>(object_id[k]) : 0.0f;
    out[8 * K + k] = seen ? 1.0f : 0.0f;
    out[9 * K + k] = via ? static_cast<float>(Mx[k]) : 0.0f;
    out[10 * K + k] = via ? static_cast<float>(My[k]) : 0.0f;
    out[11 * K + k] = via ? static_cast<float>(Mz[k]) : 0.0f;
  }
}

void WriteGroundTruthExr(const std::filesystem::path& path, const Frame& frame,
                         const std::vector<std::pair<std::string, std::string>>& metadata) {
  HOVS_REQUIRE(!frame.truth.data.empty(), path.string(), "the frame has no ground truth");
  std::vector<std::pair<std::string, std::string>> attributes;
  for (const auto& [k, v] : metadata) attributes.emplace_back("hovs:" + k, v);
  io::WriteExr(path, frame.width, frame.height,
               std::vector<std::string>(GroundTruth::kNames, GroundTruth::kNames + GroundTruth::kChannels),
               frame.truth.data.data(), attributes);
}

}  // namespace hovs::raytrace
