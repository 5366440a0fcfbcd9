// The unified model's interop and statistics: the OpenCV omnidir YAML file round-trips, OpenCV itself reads it
// and projects like hovs; the unified calibration's standard deviations cover the truth; outliers in the
// polynomial solve are found, listed and kept out of the fit.
#include <gtest/gtest.h>

#include <opencv2/ccalib/omnidir.hpp>
#include <opencv2/core.hpp>

#include <random>

#include "calib/omnidir_io.h"
#include "calib/polynomial_calibration.h"
#include "core/error.h"
#include "tests/calib/synthetic_boards.h"
#include "tests/core/test_rigs.h"

namespace hovs::calib {
namespace {

UnifiedModel<double> SomeUnified() {
  UnifiedModel<double> m;
  m.width = 2750, m.height = 2200;
  m.xi = 0.87, m.fx = 812.5, m.fy = 811.25, m.cx = 1374.3, m.cy = 1101.7, m.skew = 0.125;
  m.distortion = {-0.031, 0.0042, 1.3e-4, -2.1e-4};
  return m;
}

TEST(OmnidirIo, YamlRoundTripsAndOpenCvProjectsLikeHovs) {
  OmnidirFile f;
  f.model = SomeUnified();
  f.annulus_min = 120, f.annulus_max = 1080, f.rms_px = 0.123;
  f.stddev = {{"xi", 0.002}, {"fx", 0.5}};
  const std::string text = FormatOmnidirYaml(f);
  const OmnidirFile g = ParseOmnidirYaml(text, "memory");
  const auto& a = f.model;
  const auto& b = g.model;
  EXPECT_EQ(b.width, a.width);
  EXPECT_EQ(b.height, a.height);
  for (const auto& [x, y] : {std::pair{a.xi, b.xi},
                             {a.fx, b.fx},
                             {a.fy, b.fy},
                             {a.cx, b.cx},
                             {a.cy, b.cy},
                             {a.skew, b.skew},
                             {a.distortion.k1, b.distortion.k1},
                             {a.distortion.k2, b.distortion.k2},
                             {a.distortion.p1, b.distortion.p1},
                             {a.distortion.p2, b.distortion.p2}})
    EXPECT_NEAR(y, x, 1e-14 * std::max(1.0, std::abs(x)));
  EXPECT_DOUBLE_EQ(g.annulus_max, 1080);
  EXPECT_DOUBLE_EQ(g.rms_px, 0.123);
  EXPECT_DOUBLE_EQ(g.stddev.at("fx"), 0.5);

  // OpenCV reads the same text with its own names and projects with omnidir; its camera frame is (x, y, -z) of
  // hovs' mirror frame.
  cv::FileStorage fs(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
  cv::Mat K, D, xi;
  fs["camera_matrix"] >> K;
  fs["distortion_coefficients"] >> D;
  fs["xi"] >> xi;
  ASSERT_EQ(K.rows, 3);
  std::vector<cv::Vec3d> pts;
  std::vector<Vec2d> hovs_px;
  for (double el = -80; el <= 0; el += 10)
    for (double az = 0; az < 360; az += 30) {
      const double e = el * M_PI / 180, z = az * M_PI / 180;
      const Vec3d X(2 * std::cos(e) * std::cos(z), 2 * std::cos(e) * std::sin(z), 2 * std::sin(e));
      Vec2d uv;
      if (!a.ImgFromCam(X, &uv)) continue;
      pts.emplace_back(X.x(), X.y(), -X.z());
      hovs_px.push_back(uv);
    }
  ASSERT_GT(pts.size(), 80u);
  std::vector<cv::Vec2d> cv_px;
  cv::omnidir::projectPoints(pts, cv_px, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, xi.at<double>(0), D);
  double worst = 0;
  for (size_t k = 0; k < pts.size(); ++k)
    worst = std::max(worst, std::hypot(cv_px[k][0] - hovs_px[k].x(), cv_px[k][1] - hovs_px[k].y()));
  EXPECT_LT(worst, 1e-6) << "px between omnidir's and hovs' projections";
}

TEST(OmnidirIo, BadFilesAreRefusedByName) {
  OmnidirFile file;
  file.model = SomeUnified();
  const std::string good = FormatOmnidirYaml(file);
  EXPECT_THROW(ParseOmnidirYaml("image_width: 3\n", "plain.yaml"), Error);
  std::string no_xi = good.substr(0, good.find("xi:"));
  try {
    ParseOmnidirYaml(no_xi, "no_xi.yaml");
    FAIL() << "a file without xi was accepted";
  } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find("(xi): missing"), std::string::npos) << e.what(); }
  std::string bad_f = good;
  const size_t at = bad_f.find("data: [ ") + 8;
  bad_f.replace(at, 1, "-");  // fx negative
  EXPECT_THROW(ParseOmnidirYaml(bad_f, "bad_f.yaml"), Error);
}

TEST(UnifiedCalibration, TrueParametersInsideThreeSigmaWithHalfPixelNoise) {
  // An aligned single-viewpoint rig without lens distortion is exactly a unified camera without distortion, so
  // its corners have a true unified model.
  const auto rig = test::AlignedRig();
  const UnifiedModel<double> truth = UnifiedFromCatadioptric(rig);
  int inside = 0, trials = 0, centre_inside = 0, centre_trials = 0;
  for (unsigned seed = 30; seed < 36; ++seed) {
    const auto obs = SyntheticObservations(rig, 9, 0.5, seed);
    const PolynomialCalibration p = CalibratePolynomial(obs, rig.camera.width, rig.camera.height, {});
    const UnifiedCalibration u = CalibrateUnified(obs, rig.camera.width, rig.camera.height, p, "none", 1.0, false);
    ASSERT_TRUE(u.converged) << u.solver_report;
    ASSERT_EQ(u.stddev.size(), 5u) << "covariance unavailable";
    EXPECT_NEAR(u.rms, 0.5 * std::sqrt(2.0 * (1.0 - 59.0 / 630.0)), 0.05) << "residuals at the noise level";
    const std::pair<double, double> checks[] = {{u.model.xi - truth.xi, u.stddev.at("xi")},
                                                {u.model.fx - truth.fx, u.stddev.at("fx")},
                                                {u.model.fy - truth.fy, u.stddev.at("fy")},
                                                {u.model.cx - truth.cx, u.stddev.at("cx")},
                                                {u.model.cy - truth.cy, u.stddev.at("cy")}};
    for (const auto& [err, sd] : checks) {
      EXPECT_GT(sd, 0);
      inside += std::abs(err) <= 3 * sd;
      ++trials;
    }
    // With the distortion free as well, xi and the focal lengths become poorly determined (Mei's model trades
    // them against k1), which the standard deviations must show; the centre stays inside its 3 sigma.
    const UnifiedCalibration d = CalibrateUnified(obs, rig.camera.width, rig.camera.height, p);
    ASSERT_EQ(d.stddev.size(), 9u) << "covariance unavailable";
    EXPECT_GT(d.stddev.at("xi"), 5 * u.stddev.at("xi"));
    centre_inside += (std::abs(d.model.cx - truth.cx) <= 3 * d.stddev.at("cx")) +
                     (std::abs(d.model.cy - truth.cy) <= 3 * d.stddev.at("cy"));
    centre_trials += 2;
    if (seed == 30)
      std::printf(
          "[ figure ] unified, 0.5 px noise: xi %.5f +- %.5f (true %.5f), fx %.2f +- %.2f (true %.2f), RMS %.3f px; "
          "distortion free: xi +- %.4f, fx +- %.1f\n",
          u.model.xi, u.stddev.at("xi"), truth.xi, u.model.fx, u.stddev.at("fx"), truth.fx, u.rms, d.stddev.at("xi"),
          d.stddev.at("fx"));
  }
  EXPECT_GE(inside, trials - 1) << inside << " of " << trials;
  EXPECT_GE(centre_inside, centre_trials - 1) << centre_inside << " of " << centre_trials;
}

TEST(PolynomialCalibration, GrossCornerErrorsAreRejectedAndListed) {
  const auto rig = test::AlignedRig();
  auto obs = SyntheticObservations(rig, 9, 0.1, 41);
  // Three corners moved by 2 to 6 px (a detector snapping to the wrong saddle).
  const std::pair<int, int> bad[] = {{1, 7}, {4, 20}, {8, 0}};
  const Vec2d shift[] = {Vec2d(2.0, -1.0), Vec2d(-4.0, 3.0), Vec2d(0.0, 6.0)};
  for (int k = 0; k < 3; ++k) obs[bad[k].first].pixels[bad[k].second] += shift[k];
  PolynomialCalibrationOptions keep;
  keep.outlier_sigmas = 0;
  const PolynomialCalibration all = CalibratePolynomial(obs, rig.camera.width, rig.camera.height, keep);
  const PolynomialCalibration r = CalibratePolynomial(obs, rig.camera.width, rig.camera.height, {});
  EXPECT_TRUE(all.outliers.empty());
  ASSERT_EQ(r.outliers.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    bool listed = false;
    for (const auto& o : r.outliers) listed |= o.image_index == bad[k].first && o.corner == bad[k].second;
    EXPECT_TRUE(listed) << "image " << bad[k].first << " corner " << bad[k].second;
    EXPECT_FALSE(r.inlier[bad[k].first][bad[k].second]);
  }
  for (const auto& o : r.outliers) EXPECT_GT(o.residual_after_px, 1.5) << "still off after the final solve";
  EXPECT_LT(r.rms, 0.16) << "inliers at the noise level (0.1 px per axis)";
  EXPECT_GT(all.rms, 2 * r.rms);
  const auto kept = InlierObservations(obs, r);
  EXPECT_EQ(kept[4].pixels.size(), obs[4].pixels.size() - 1);
  std::printf(
      "[ figure ] 3 corners moved 2.2-6 px: RMS %.3f px with them, %.3f px after rejection (threshold %.2f px)\n",
      all.rms, r.rms, r.outlier_threshold_px);
}

}  // namespace
}  // namespace hovs::calib
