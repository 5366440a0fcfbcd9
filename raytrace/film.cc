#include "raytrace/film.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <set>
#include <sstream>

#include <tbb/parallel_for.h>

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

namespace {
// Each group's first channel in GroundTruth::kNames and its channel count.
struct GroupSpan {
  const char* name;
  int first, count;
};
constexpr GroupSpan kGroups[] = {{"Z", 0, 1}, {"P", 1, 3}, {"N", 4, 3}, {"id", 7, 1}, {"mask", 8, 1}, {"M", 9, 3}};
}  // namespace

const std::vector<std::string>& TruthFileOptions::AllGroups() {
  static const std::vector<std::string> all = {"Z", "P", "N", "id", "mask", "M"};
  return all;
}

const std::vector<std::string>& TruthFileOptions::Compressions() {
  static const std::vector<std::string> all = {"none", "rle", "zips", "zip", "piz"};
  return all;
}

std::vector<std::string> TruthFileOptions::ParseGroups(const std::string& text, const std::string& where) {
  if (text == "default") return TruthFileOptions{}.groups;
  if (text == "all") return AllGroups();
  if (text == "none") return {};
  std::set<std::string> wanted;
  std::stringstream list(text);
  std::string word;
  while (std::getline(list, word, ',')) {
    HOVS_REQUIRE(std::find(AllGroups().begin(), AllGroups().end(), word) != AllGroups().end(), where,
                 "unknown ground-truth channel '", word,
                 "' (expected default, all, none, or a list of Z, P, N, id, mask, M separated by commas)");
    HOVS_REQUIRE(wanted.insert(word).second, where, "the channel '", word, "' is listed twice");
  }
  HOVS_REQUIRE(!wanted.empty() && text.back() != ',', where, "expected default, all, none, or a list of Z, P, N, id, ",
               "mask, M separated by commas (got '", text, "')");
  std::vector<std::string> groups;
  for (const auto& g : AllGroups())
    if (wanted.count(g)) groups.push_back(g);
  return groups;
}

std::vector<int> TruthFileOptions::Channels() const {
  std::vector<int> channels;
  for (const GroupSpan& g : kGroups)
    if (std::find(groups.begin(), groups.end(), g.name) != groups.end())
      for (int c = 0; c < g.count; ++c) channels.push_back(g.first + c);
  return channels;
}

std::string TruthFileOptions::GroupsText() const {
  std::string text;
  for (const auto& g : groups) text += (text.empty() ? "" : ",") + g;
  return text.empty() ? "none" : text;
}

void TruthFileOptions::Check(const std::string& where) const {
  std::string list;
  for (const auto& g : groups) list += (list.empty() ? "" : ",") + g;
  if (!list.empty())
    HOVS_REQUIRE(ParseGroups(list, where + ".truth_channels") == groups, where + ".truth_channels",
                 "lists its channels out of order or twice (", list, ")");
  HOVS_REQUIRE(std::find(Compressions().begin(), Compressions().end(), compression) != Compressions().end(),
               where + ".truth_compression", "unknown OpenEXR compression '", compression,
               "' (none, rle, zips, zip, piz)");
}

void WriteGroundTruthExr(const std::filesystem::path& path, const Frame& frame,
                         const std::vector<std::pair<std::string, std::string>>& metadata,
                         const TruthFileOptions& file) {
  HOVS_REQUIRE(!frame.truth.data.empty(), path.string(), "the frame has no ground truth");
  const std::vector<int> channels = file.Channels();
  HOVS_REQUIRE(!channels.empty(), path.string(), "no ground-truth channel is selected");
  std::vector<std::pair<std::string, std::string>> attributes;
  for (const auto& [k, v] : metadata) attributes.emplace_back("hovs:" + k, v);
  std::vector<std::string> names;
  for (int c : channels) names.push_back(GroundTruth::kNames[c]);
  const int n = static_cast<int>(channels.size());
  if (n == GroundTruth::kChannels) {
    io::WriteExr(path, frame.width, frame.height, names, frame.truth.data.data(), attributes, file.compression);
    return;
  }
  // The selected channels, interleaved as the file stores them (row by row in parallel: 6 Mpx a full frame).
  const std::size_t width = static_cast<std::size_t>(frame.width);
  PixelBuffer picked(width * frame.height * n);
  tbb::parallel_for(0, frame.height, [&](int y) {
    const float* in = frame.truth.data.data() + y * width * GroundTruth::kChannels;
    float* out = picked.data() + y * width * n;
    for (std::size_t x = 0; x < width; ++x)
      for (int k = 0; k < n; ++k) out[x * n + k] = in[x * GroundTruth::kChannels + channels[k]];
  });
  io::WriteExr(path, frame.width, frame.height, names, picked.data(), attributes, file.compression);
}

}  // namespace hovs::raytrace
