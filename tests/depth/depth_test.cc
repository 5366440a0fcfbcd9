// Depth from two units, against ground truth: sparse triangulation of points at 1-5 m (true models, then
// polynomial models), the law of sines, rectification (epipolar rows, range from disparity), dense depth of a
// rendered street scene against the renderer's range channel, per distance band.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <tuple>

#include "core/model_fit.h"
#include "depth/stereo.h"
#include "raytrace/render.h"
#include "scenes/scene_config.h"
#include "tests/core/test_rigs.h"

namespace hovs::depth {
namespace {

constexpr double kDeg = M_PI / 180;

scenes::SceneConfig Street() { return scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/street.yaml"); }

StereoRig RigOf(const scenes::SceneConfig& cfg) {
  const auto& u = cfg.description.units;
  return {AnyModel::Exact(u[0].rig), AnyModel::Exact(u[1].rig),
          u[1].world_from_mirror.Inverse() * u[0].world_from_mirror};
}

// World points around the rig at 1-5 m from the left viewpoint, below the horizon, away from the baseline.
std::vector<Vec3d> PointsLeft(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> az(25 * kDeg, 155 * kDeg), el(-50 * kDeg, -8 * kDeg), r(1.0, 5.0);
  std::vector<Vec3d> out;
  for (int i = 0; i < n; ++i) {
    const double a = (i % 2 ? 1 : -1) * az(rng), e = el(rng), d = r(rng);
    out.emplace_back(d * std::cos(e) * std::cos(a), d * std::cos(e) * std::sin(a), d * std::sin(e));
  }
  return out;
}

TEST(Sparse, LawOfSinesIsTheTriangulationOfAParallelRig) {
  const auto rig0 = test::AlignedRig();
  StereoRig rig{AnyModel::Exact(rig0), AnyModel::Exact(rig0), Rigid3d::Translation(Vec3d(-0.64, 0, 0))};
  EXPECT_NEAR(rig.Baseline(), 0.64, 1e-12);
  const Vec3d X(1.3, 2.1, 0.0);  // a horizontal ray from both units
  const Triangulation t = Triangulate(rig, X, X - Vec3d(0.64, 0, 0), 0);
  ASSERT_TRUE(t.ok);
  const double thl = std::acos(X.normalized().x()), thr = std::acos((X - Vec3d(0.64, 0, 0)).normalized().x());
  EXPECT_NEAR(t.range_left, LawOfSinesRange(0.64, thl, thr), 1e-12);
  EXPECT_NEAR(t.range_left, X.norm(), 1e-12);
}

// Bearings of exact projections with pixel noise, back-projected through `models`.
struct SparseResult {
  double worst_rel = 0, rms_rel = 0, z2 = 0;
  int n = 0;
};
SparseResult SparseRun(const scenes::SceneConfig& cfg, const StereoRig& models, double noise_px, unsigned seed) {
  const auto& u = cfg.description.units;
  const StereoRig truth = RigOf(cfg);
  const Rigid3d right_from_left = truth.right_from_left;
  std::mt19937 rng(seed);
  std::normal_distribution<double> N(0, noise_px);
  SparseResult r;
  double sum2 = 0;
  for (const Vec3d& X : PointsLeft(400, seed)) {
    Vec2d pl, pr;
    if (u[0].rig.ImgFromMirror(X, &pl) != ProjectionStatus::kOk) continue;
    if (u[1].rig.ImgFromMirror(right_from_left * X, &pr) != ProjectionStatus::kOk) continue;
    pl += Vec2d(N(rng), N(rng));
    pr += Vec2d(N(rng), N(rng));
    Vec3d bl, br;
    if (!models.left.MirrorFromImg(pl, &bl) || !models.right.MirrorFromImg(pr, &br)) continue;
    // Angular noise of this pixel: the angle between neighbouring pixels' bearings times the pixel noise.
    Vec3d bl1;
    models.left.MirrorFromImg(pl + Vec2d(1, 0), &bl1);
    const double sigma_angle = std::acos(std::clamp(bl.dot(bl1), -1.0, 1.0)) * noise_px;
    const Triangulation t = Triangulate(models, bl, br, sigma_angle);
    if (!t.ok) continue;
    const double rel = std::abs(t.range_left - X.norm()) / X.norm();
    r.worst_rel = std::max(r.worst_rel, rel);
    sum2 += rel * rel;
    if (t.sigma_range > 0) r.z2 += std::pow((t.range_left - X.norm()) / t.sigma_range, 2);
    ++r.n;
  }
  r.rms_rel = std::sqrt(sum2 / r.n);
  r.z2 /= r.n;
  return r;
}

TEST(Sparse, PointsAtOneToFiveMetresWithTrueAndPolynomialModels) {
  // The street rig with the right unit aligned: a polynomial model (fitted here to each true rig) needs a single
  // viewpoint.
  auto cfg = Street();
  auto& right = cfg.description.units[1].rig;
  right.cam_from_mirror = scenes::MisalignedCamFromMirror(right.mirror, Vec3d::Zero(), Vec3d::Zero(), 0);
  const StereoRig truth = RigOf(cfg);
  EXPECT_NEAR(truth.Baseline(), 0.641, 0.002);
  StereoRig poly = truth;
  poly.left = AnyModel::Polynomial(PolynomialFromCatadioptric(cfg.description.units[0].rig, 5));
  poly.right = AnyModel::Polynomial(PolynomialFromCatadioptric(cfg.description.units[1].rig, 5));
  // Pixel noise 0.05 px: the corner accuracy measured on renders (cornerSubPix, tests/raytrace); and twice that.
  const SparseResult exact = SparseRun(cfg, truth, 0.05, 3), fitted = SparseRun(cfg, poly, 0.05, 3);
  const SparseResult exact2 = SparseRun(cfg, truth, 0.1, 3), fitted2 = SparseRun(cfg, poly, 0.1, 3);
  for (const auto& [noise, e, f] :
       {std::tuple<double, const SparseResult&, const SparseResult&>{0.05, exact, fitted}, {0.1, exact2, fitted2}})
    std::printf(
        "[ figure ] sparse, %.2f px noise, %d points at 1-5 m: true models worst %.5f %% (RMS %.5f %%, "
        "mean squared z %.2f); fitted polynomial models (N = 5) worst %.5f %% (RMS %.5f %%)\n",
        noise, e.n, 100 * e.worst_rel, 100 * e.rms_rel, e.z2, 100 * f.worst_rel, 100 * f.rms_rel);
  EXPECT_GT(exact.n, 300);
  EXPECT_LE(exact.worst_rel, 0.005);
  EXPECT_LE(fitted.worst_rel, 0.01);
  EXPECT_LE(exact2.rms_rel, 0.005);
  // The propagated sigma describes the error (mean squared normalised error near 1).
  EXPECT_GT(exact.z2, 0.5);
  EXPECT_LT(exact.z2, 2.0);
}

TEST(Rectification, EpipolarRowsAndRangeFromDisparity) {
  const auto cfg = Street();
  const StereoRig rig = RigOf(cfg);
  RectifyOptions ro;
  ro.width = 1024, ro.height = 256;
  const Rectification r = Rectify(rig, ro);
  const auto& vl = r.left.views[0].view;
  const auto& vr = r.right.views[0].view;
  double worst_row = 0, worst_rel = 0;
  int n = 0;
  for (const Vec3d& X : PointsLeft(300, 9)) {
    Vec2d ul, ur;
    ASSERT_TRUE(vl.ImgFromMirror(X, &ul));
    ASSERT_TRUE(vr.ImgFromMirror(rig.right_from_left * X, &ur));
    worst_row = std::max(worst_row, std::abs(ul.y() - ur.y()));
    const double d = ul.x() - ur.x();
    ASSERT_GT(d, 0);
    const double range = RangeFromDisparity(r.baseline, r.ThetaAt(ul.x()), d * r.dtheta);
    worst_rel = std::max(worst_rel, std::abs(range - X.norm()) / X.norm());
    ++n;
  }
  EXPECT_LT(worst_row, 1e-6) << "epipolar curves must be rows";
  EXPECT_LT(worst_rel, 1e-9);
  // Every rectified pixel of the lower half-space that the mirror sees is filled.
  std::vector<float> mx, my;
  r.left.DecodeView(0, &mx, &my);
  const double filled = double(std::count_if(mx.begin(), mx.end(), [](float x) { return x >= 0; })) / mx.size();
  EXPECT_GT(filled, 0.5);
}

TEST(Dense, StreetSceneAgainstTheRangeChannel) {
  auto cfg = Street();
  const StereoRig rig = RigOf(cfg);
  const raytrace::RayScene scene(cfg.description);
  raytrace::RenderOptions ro;
  ro.samples = 4;
  ro.ground_truth = true;
  const raytrace::Frame fl = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  ro.ground_truth = false;
  const raytrace::Frame fr = raytrace::Render(scene, raytrace::ViewCamera::Unit(1), ro);
  const auto to8 = [](const raytrace::Frame& f) {
    std::vector<uint8_t> b(f.rgb.size());
    for (size_t k = 0; k < b.size(); ++k) b[k] = uint8_t(std::lround(std::clamp(f.rgb[k], 0.f, 1.f) * 255));
    return b;
  };
  const auto l8 = to8(fl), r8 = to8(fr);
  RectifyOptions rop;  // 2048 x 512, the lower half-space
  const Rectification rect = Rectify(rig, rop);
  unwrap::Remapper ml(rect.left), mr(rect.right);
  std::vector<unwrap::Image8> left, right;
  ml.Run({l8.data(), fl.width, fl.height, size_t(fl.width) * 3, unwrap::PixelFormat::kRgb8},
         unwrap::Interpolation::kBilinear, &left);
  mr.Run({r8.data(), fr.width, fr.height, size_t(fr.width) * 3, unwrap::PixelFormat::kRgb8},
         unwrap::Interpolation::kBilinear, &right);
  // Ground truth: the range channel (Z) of the left render at each rectified pixel's source pixel.
  std::vector<float> mx, my;
  rect.left.DecodeView(0, &mx, &my);
  for (const bool c2f : {false, true}) {
    DenseOptions dop;
    dop.coarse_to_fine = c2f;
    const DenseDepth d = ComputeDenseDepth(rect, left[0], right[0], dop);
    struct Band {
      double lo, hi;
      std::vector<double> rel;
      int pixels = 0;
    };
    std::vector<Band> bands = {{1, 2, {}}, {2, 4, {}}, {4, 8, {}}, {8, 16, {}}};
    for (size_t k = 0; k < mx.size(); ++k) {
      if (mx[k] < 0) continue;
      const int sx = int(std::lround(mx[k])), sy = int(std::lround(my[k]));
      const float* gt = &fl.truth.data[(size_t(sy) * fl.width + sx) * raytrace::GroundTruth::kChannels];
      const double z = gt[0];
      if (!std::isfinite(z)) continue;
      for (auto& b : bands) {
        if (z < b.lo || z >= b.hi) continue;
        ++b.pixels;
        if (d.valid[k]) b.rel.push_back(std::abs(d.range[k] - z) / z);
      }
    }
    std::printf("[ figure ] dense depth, street scene, 2048 x 512, %s, %d disparities: %.0f ms (matching %.0f ms)\n",
                c2f ? "coarse to fine (SGBM at half resolution + block search)" : "SGBM 3-way", dop.num_disparities,
                d.total_ms, d.match_ms);
    std::printf("[ figure ]   band (m)   pixels  valid   median rel. error   within 5 %% (of all pixels)\n");
    for (auto& b : bands) {
      std::sort(b.rel.begin(), b.rel.end());
      const double median = b.rel.empty() ? NAN : b.rel[b.rel.size() / 2];
      const double within = double(std::count_if(b.rel.begin(), b.rel.end(), [](double e) { return e <= 0.05; }));
      std::printf("[ figure ]   %4.0f-%-4.0f %8d %6.1f %%   %8.2f %%            %6.1f %%\n", b.lo, b.hi, b.pixels,
                  100.0 * b.rel.size() / std::max(1, b.pixels), 100 * median, 100 * within / std::max(1, b.pixels));
    }
    // Thresholds on the bands that carry most of the scene (road, kerbs, cars): median error and the fraction of
    // all pixels of the band with a range within 5 %.
    for (int i = 0; i < 3; ++i) {
      ASSERT_GT(bands[i].rel.size(), 1000u) << bands[i].lo << "-" << bands[i].hi << " m";
      EXPECT_LT(bands[i].rel[bands[i].rel.size() / 2], 0.02) << bands[i].lo << "-" << bands[i].hi << " m";
      const double within =
          double(std::count_if(bands[i].rel.begin(), bands[i].rel.end(), [](double e) { return e <= 0.05; }));
      EXPECT_GT(within / bands[i].pixels, 0.7) << bands[i].lo << "-" << bands[i].hi << " m";
    }
  }
}

}  // namespace
}  // namespace hovs::depth
