#include "depth/evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <tuple>

#include "depth/stereo.h"

namespace hovs::depth {
namespace {

double RotationAngleDeg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return 2 * std::asin(std::min(1.0, (a * b.conjugate()).vec().norm())) * 180 / M_PI;
}

// The upper middle of sorted values, and the 95th percentile as index floor(0.95 n).
double SortedMedian(const std::vector<double>& v) { return v[v.size() / 2]; }
double SortedP95(const std::vector<double>& v) { return v[std::min(v.size() - 1, v.size() * 95 / 100)]; }

nlohmann::json Listing(const std::vector<const SparseDepthPoint*>& ws) {
  nlohmann::json wl = nlohmann::json::array();
  for (size_t k = 0; k < std::min<size_t>(10, ws.size()); ++k) {
    const SparseDepthPoint& w = *ws[k];
    wl.push_back({{"pair", w.pair},
                  {"corner", w.corner},
                  {"rel_error", std::abs(w.rel_error)},
                  {"range_m", w.range_m},
                  {"angle_to_baseline_deg", w.angle_to_baseline_deg},
                  {"predicted_sigma_rel_0.1px", w.predicted_sigma_rel},
                  {"ray_gap_mm", w.ray_gap_mm},
                  {"left_corner_error_px", w.left_corner_error_px},
                  {"right_corner_error_px", w.right_corner_error_px},
                  {"left_refinement", w.left_from_edges ? "edges" : "window"},
                  {"right_refinement", w.right_from_edges ? "edges" : "window"}});
  }
  return wl;
}

}  // namespace

PoseError CompareWithTruth(const Rigid3d& right_from_left, double baseline, const Rigid3d& truth) {
  PoseError e;
  e.true_baseline_m = truth.translation.norm();
  e.baseline_error_mm = 1e3 * (baseline - truth.translation.norm());
  e.translation_error_mm = 1e3 * (right_from_left.translation - truth.translation).norm();
  e.rotation_error_deg = RotationAngleDeg(right_from_left.rotation, truth.rotation);
  return e;
}

SparseDepthEvaluation EvaluateSparseDepth(const StereoDataset& d, const AnyModel& left, const AnyModel& right,
                                          const StereoCalibration& c, const std::vector<StereoPairObservation>& pairs) {
  SparseDepthEvaluation out;
  const StereoRig rig{left, right, c.right_from_left};
  const double px_rad = 0.1 * (M_PI / 2) / std::max(1, d.left_unit.rig.camera.width / 2);  // ~0.1 px at the rim
  const Vec3d base_dir = c.right_from_left.Inverse().translation.normalized();
  std::set<std::tuple<std::string, std::string, int>> outliers;
  for (const auto& x : c.outliers) outliers.insert({x.pair, x.unit, x.corner});
  for (const StereoFrame& f : d.frames) {
    if (!f.world_from_board) continue;
    const auto it = std::find_if(pairs.begin(), pairs.end(), [&](const auto& p) { return p.name == f.name; });
    if (it == pairs.end()) continue;
    const Rigid3d left_from_board = d.left_unit.world_from_mirror.Inverse() * *f.world_from_board;
    const Rigid3d right_from_board = d.right_unit.world_from_mirror.Inverse() * *f.world_from_board;
    std::map<int, const CornerObservation*> right_corners;
    for (const auto& p : it->right) right_corners[p.id] = &p;
    for (const auto& p : it->left) {
      const auto r = right_corners.find(p.id);
      const auto b = d.board.find(p.id);
      if (r == right_corners.end() || b == d.board.end()) continue;
      // Corners the calibration rejected as mis-detected (listed in stereo.json) are not triangulated.
      if (outliers.count({f.name, "left", p.id}) || outliers.count({f.name, "right", p.id})) {
        ++out.excluded_outlier_corners;
        continue;
      }
      Vec3d ol, bl, orr, br;
      if (!left.RayFromImg(p.pixel, &ol, &bl) || !right.RayFromImg(r->second->pixel, &orr, &br)) continue;
      const auto tri = Triangulate(rig, ol, bl, orr, br, px_rad);
      if (!tri.ok) continue;
      const Vec3d X = left_from_board * b->second;
      SparseDepthPoint s;
      s.pair = f.name, s.corner = p.id;
      s.range_m = X.norm();
      s.rel_error = (tri.range_left - s.range_m) / s.range_m;
      s.angle_to_baseline_deg = std::acos(std::clamp(X.normalized().dot(base_dir), -1.0, 1.0)) * 180 / M_PI;
      s.predicted_sigma_rel = tri.sigma_range / s.range_m, s.ray_gap_mm = 1e3 * tri.gap;
      Vec2d tl, tr;
      if (left.ImgFromPointUnbounded(X, &tl)) s.left_corner_error_px = (tl - p.pixel).norm();
      if (right.ImgFromPointUnbounded(right_from_board * b->second, &tr))
        s.right_corner_error_px = (tr - r->second->pixel).norm();
      s.left_from_edges = p.from_edges, s.right_from_edges = r->second->from_edges;
      out.points.push_back(s);
    }
  }
  return out;
}

nlohmann::json SparseDepthJson(const SparseDepthEvaluation& e) {
  if (e.points.empty()) return nullptr;
  struct Band {
    double lo, hi;
    std::vector<double> rel;
  };
  std::vector<Band> bands = {{0, 1, {}}, {1, 2, {}}, {2, 3, {}}, {3, 5, {}}, {5, 1e9, {}}};
  double worst = 0, ss = 0;
  std::vector<double> all;
  for (const auto& p : e.points) {
    const double rel = std::abs(p.rel_error);
    for (auto& band : bands)
      if (p.range_m >= band.lo && p.range_m < band.hi) band.rel.push_back(rel);
    worst = std::max(worst, rel), ss += p.rel_error * p.rel_error;
    all.push_back(rel);
  }
  nlohmann::json tab = nlohmann::json::array();
  for (auto& band : bands) {
    if (band.rel.empty()) continue;
    std::sort(band.rel.begin(), band.rel.end());
    tab.push_back({{"range_m", {band.lo, band.hi > 1e8 ? -1 : band.hi}},
                   {"points", band.rel.size()},
                   {"median_rel_error", SortedMedian(band.rel)},
                   {"max_rel_error", band.rel.back()}});
  }
  const size_t n = e.points.size();
  std::sort(all.begin(), all.end());
  nlohmann::json j = {{"points", n},
                      {"rms_rel_error", std::sqrt(ss / n)},
                      {"max_rel_error", worst},
                      {"median_rel_error", SortedMedian(all)},
                      {"p95_rel_error", SortedP95(all)},
                      {"excluded_outlier_corners", e.excluded_outlier_corners},
                      {"bands", tab}};
  std::vector<const SparseDepthPoint*> by_error;
  for (const auto& p : e.points) by_error.push_back(&p);
  std::stable_sort(by_error.begin(), by_error.end(), [](const SparseDepthPoint* a, const SparseDepthPoint* b) {
    return std::abs(a->rel_error) > std::abs(b->rel_error);
  });
  std::vector<const SparseDepthPoint*> cond_worst;
  std::vector<double> cond;
  for (const SparseDepthPoint* p : by_error)
    if (p->angle_to_baseline_deg >= kConditionedAngleDeg && p->angle_to_baseline_deg <= 180 - kConditionedAngleDeg)
      cond.push_back(std::abs(p->rel_error)), cond_worst.push_back(p);
  j["worst_points"] = Listing(by_error);
  if (!cond.empty()) {
    std::sort(cond.begin(), cond.end());
    j["conditioned"] = {{"min_angle_to_baseline_deg", kConditionedAngleDeg},
                        {"points", cond.size()},
                        {"median_rel_error", SortedMedian(cond)},
                        {"p95_rel_error", SortedP95(cond)},
                        {"max_rel_error", cond.back()},
                        {"worst_points", Listing(cond_worst)}};
  }
  return j;
}

std::string SparseDepthCsv(const SparseDepthEvaluation& e) {
  std::string s =
      "pair,corner,range_m,angle_to_baseline_deg,rel_error,predicted_sigma_rel_0.1px,ray_gap_mm,"
      "left_corner_error_px,right_corner_error_px\n";
  char line[256];
  for (const auto& p : e.points) {
    std::snprintf(line, sizeof line, "%s,%d,%.6f,%.4f,%.8f,%.8f,%.5f,%.5f,%.5f\n", p.pair.c_str(), p.corner, p.range_m,
                  p.angle_to_baseline_deg, p.rel_error, p.predicted_sigma_rel, p.ray_gap_mm, p.left_corner_error_px,
                  p.right_corner_error_px);
    s += line;
  }
  return s;
}

double DenseBand::Median() const { return rel.empty() ? NAN : rel[rel.size() / 2]; }

double DenseBand::WithinFraction(double limit) const {
  return double(std::count_if(rel.begin(), rel.end(), [&](double e) { return e <= limit; })) / std::max(1, pixels);
}

DenseDepthEvaluation EvaluateDenseDepth(const Rectification& rect, const DenseDepth& d, const std::vector<float>& Z,
                                        int truth_width) {
  DenseDepthEvaluation e;
  std::vector<float> mx, my;
  rect.left.DecodeView(0, &mx, &my);
  for (const auto& [lo, hi] : std::vector<std::pair<double, double>>{{1, 2}, {2, 4}, {4, 8}, {8, 16}, {16, 64}}) {
    DenseBand b;
    b.lo = lo, b.hi = hi;
    e.bands.push_back(b);
  }
  e.error_map.assign(size_t(d.width) * d.height * 3, 0.25f);
  for (size_t k = 0; k < mx.size(); ++k) {
    if (mx[k] < 0) continue;
    const double z = Z[size_t(std::lround(my[k])) * truth_width + size_t(std::lround(mx[k]))];
    if (!std::isfinite(z)) continue;
    const float t = d.valid[k] ? float(std::min(1.0, std::abs(d.range[k] - z) / z / 0.05)) : -1.f;
    float* c = &e.error_map[3 * k];
    c[0] = t < 0 ? 0.f : t, c[1] = t < 0 ? 0.f : 1 - std::abs(2 * t - 1), c[2] = t < 0 ? 0.f : 1 - t;
    for (auto& b : e.bands)
      if (z >= b.lo && z < b.hi) {
        ++b.pixels;
        if (d.valid[k]) b.rel.push_back(std::abs(d.range[k] - z) / z);
      }
  }
  for (auto& b : e.bands) std::sort(b.rel.begin(), b.rel.end());
  return e;
}

nlohmann::json DenseBandsJson(const DenseDepthEvaluation& e) {
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& b : e.bands)
    rows.push_back({{"band_m", {b.lo, b.hi}},
                    {"pixels", b.pixels},
                    {"valid_fraction", b.ValidFraction()},
                    {"median_relative_error", b.rel.empty() ? nlohmann::json() : nlohmann::json(b.Median())},
                    {"within_5_percent_fraction", b.WithinFraction(0.05)}});
  return rows;
}

std::string DenseBandsTable(const DenseDepthEvaluation& e) {
  std::string table = "  band (m)    pixels   valid   median rel. error   within 5 % (of all)\n";
  for (const auto& b : e.bands) {
    char line[160];
    std::snprintf(line, sizeof line, "  %5.0f-%-5.0f %8d %6.1f %%   %8.2f %%          %6.1f %%\n", b.lo, b.hi, b.pixels,
                  100 * b.ValidFraction(), 100 * b.Median(), 100 * b.WithinFraction(0.05));
    table += line;
  }
  return table;
}

void SubsampledCloud(const Rectification& rect, const DenseDepth& d, const unwrap::Image8& left, int max_points,
                     std::vector<ColouredPoint>* points, std::vector<float>* sigmas) {
  const size_t nvalid = std::count(d.valid.begin(), d.valid.end(), 1);
  const size_t cap = static_cast<size_t>(std::max(1, max_points));
  const size_t step = std::max<size_t>(1, (nvalid + cap - 1) / cap);  // rounded up: at most max_points points
  size_t seen = 0;
  for (int v = 0; v < d.height; ++v)
    for (int u = 0; u < d.width; ++u) {
      const size_t k = size_t(v) * d.width + u;
      if (!d.valid[k] || (seen++ % step)) continue;
      ColouredPoint p;
      p.p = rect.LeftBearing(u, v) * d.range[k];
      for (int c = 0; c < 3; ++c) p.rgb[c] = left.data[k * left.channels + (left.channels == 3 ? c : 0)];
      points->push_back(p);
      sigmas->push_back(d.sigma[k]);
    }
}

}  // namespace hovs::depth
