// The renderer as the judge: ground-truth corners agree with tracing back through the mirror (aligned and
// misaligned rigs), corners found in a noise-free render agree with the ground truth, the range channel of a
// plane is analytic, the mirror mask is the core's, the sensor model does what it says, a golden render.
#include <gtest/gtest.h>

#include <map>
#include <optional>

#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstring>
#include <random>
#include <filesystem>

#include <unistd.h>

#include "calib/checkerboard_edges.h"
#include "core/error.h"
#include "core/large_pages.h"
#include "raytrace/render.h"
#include "scenes/ground_truth.h"
#include "scenes/scene_config.h"
#include "io/image_io.h"

namespace hovs {
namespace {

using raytrace::RayScene;
using scenes::SceneConfig;
constexpr double kDeg = M_PI / 180;

SceneConfig BoardScene(bool misaligned) {
  SceneConfig cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_board.yaml");
  if (misaligned) {
    auto& rig = cfg.description.units[0].rig;
    rig.cam_from_mirror =
        scenes::MisalignedCamFromMirror(rig.mirror, Vec3d(1.0 * kDeg, 0.3 * kDeg, 0), Vec3d(0.001, -0.0005, 0), 0.001);
  }
  return cfg;
}

// The reference board scene seen by a camera of the same field of view with pixels `shrink` times larger.
SceneConfig SmallBoardScene(int shrink) {
  SceneConfig cfg = BoardScene(false);
  cfg.description.units[0].rig.camera =
      PinholeCamera<double>::FromPhysical(0.016, 4.54e-6 * shrink, 2750 / shrink, 2200 / shrink);
  return cfg;
}

// Region of the image around the visible corners of the first board.
raytrace::RenderOptions::Region CornerRegion(const std::vector<scenes::CornerTruth>& corners, int pad) {
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const auto& c : corners) {
    if (c.status != "visible") continue;
    x0 = std::min(x0, c.pixel.x()), y0 = std::min(y0, c.pixel.y());
    x1 = std::max(x1, c.pixel.x()), y1 = std::max(y1, c.pixel.y());
  }
  return {static_cast<int>(x0) - pad, static_cast<int>(y0) - pad, static_cast<int>(x1) + pad,
          static_cast<int>(y1) + pad};
}

class GroundTruth : public ::testing::TestWithParam<bool> {};

TEST_P(GroundTruth, CornerProjectionAgreesWithTracingBackThroughTheMirror) {
  const SceneConfig cfg = BoardScene(GetParam());
  const RayScene scene(cfg.description);
  const auto& unit = scene.description().units[0];
  EXPECT_EQ(unit.rig.IsSingleViewpoint(), !GetParam());
  const auto corners = scenes::BoardCornerTruth(scene, cfg.boards[0], 0);
  ASSERT_EQ(corners.size(), 35u);
  double worst = 0;
  for (const auto& c : corners) {
    ASSERT_EQ(c.status, "visible") << c.id;
    const auto trace = [&](const Vec2d& uv) {
      Vec3d M, d;
      EXPECT_TRUE(unit.rig.RayFromImg(uv, &M, &d));
      return scene.Trace(unit.world_from_mirror * M, unit.world_from_mirror.Rotate(d), 1e-5, 0);
    };
    const raytrace::Hit h = trace(c.pixel);
    ASSERT_EQ(h.object_id, cfg.boards[0].object_id) << "corner " << c.id << " traces to another object";
    const double footprint = (trace(c.pixel + Vec2d(1, 0)).point - h.point).norm();
    worst = std::max(worst, (h.point - c.world).norm() / footprint);
  }
  EXPECT_LT(worst, 1e-3) << "pixels";
  RecordProperty("worst_px", std::to_string(worst));
}
INSTANTIATE_TEST_SUITE_P(AlignedAndMisaligned, GroundTruth, ::testing::Values(false, true));

TEST(Render, CornersFoundInANoiseFreeRenderMatchTheGroundTruth) {
  for (bool misaligned : {false, true}) {
    SceneConfig cfg = BoardScene(misaligned);
    const RayScene scene(cfg.description);
    const auto corners = scenes::BoardCornerTruth(scene, cfg.boards[0], 0);
    raytrace::RenderOptions ro;
    ro.samples = 64;
    ro.ground_truth = false;
    ro.region = CornerRegion(corners, 40);
    const raytrace::Frame f = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
    cv::Mat grey(f.height, f.width, CV_32F);
    for (int y = 0; y < f.height; ++y)
      for (int x = 0; x < f.width; ++x) grey.at<float>(y, x) = f.rgb[3 * (static_cast<size_t>(y) * f.width + x)];
    std::vector<cv::Point2f> pts;
    for (const auto& c : corners)
      pts.emplace_back(static_cast<float>(c.pixel.x() + 0.6), static_cast<float>(c.pixel.y() - 0.4));
    cv::cornerSubPix(grey, pts, cv::Size(4, 4), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 200, 1e-5));
    double sum2 = 0;
    for (size_t i = 0; i < pts.size(); ++i)
      sum2 += std::pow(pts[i].x - corners[i].pixel.x(), 2) + std::pow(pts[i].y - corners[i].pixel.y(), 2);
    const double rms = std::sqrt(sum2 / pts.size());
    EXPECT_LE(rms, 0.1) << (misaligned ? "misaligned" : "aligned");
    std::printf("[ figure ] corner RMS (cornerSubPix vs ground truth, 64 spp, %s rig): %.4f px\n",
                misaligned ? "misaligned" : "aligned", rms);
    RecordProperty(misaligned ? "rms_misaligned_px" : "rms_aligned_px", std::to_string(rms));

    // The same corners from the board's edges (hovs' detector's default refinement), in the 8-bit image: the
    // issue's goal of 0.05 px.
    cv::Mat grey8;
    grey.convertTo(grey8, CV_8U, 255.0);
    double xmin = HUGE_VAL, ymin = HUGE_VAL;
    for (const auto& c : corners) xmin = std::min(xmin, c.board_xy.x()), ymin = std::min(ymin, c.board_xy.y());
    const double square = cfg.boards[0].spec.square;
    const int cols = cfg.boards[0].spec.squares_x - 1, rows = cfg.boards[0].spec.squares_y - 1;
    std::vector<std::optional<Vec2d>> grid(static_cast<size_t>(cols) * rows);
    std::vector<Vec2d> truth(grid.size());
    for (size_t i = 0; i < corners.size(); ++i) {
      const int gi = static_cast<int>(std::lround((corners[i].board_xy.x() - xmin) / square));
      const int gj = static_cast<int>(std::lround((corners[i].board_xy.y() - ymin) / square));
      ASSERT_TRUE(gi >= 0 && gi < cols && gj >= 0 && gj < rows);
      grid[static_cast<size_t>(gj) * cols + gi] = Vec2d(pts[i].x, pts[i].y);
      truth[static_cast<size_t>(gj) * cols + gi] = corners[i].pixel;
    }
    const auto refined = calib::RefineCheckerboardCornersByEdges(grey8, cols, rows, &grid);
    double se = 0;
    int from_edges = 0;
    for (size_t k = 0; k < grid.size(); ++k) se += (*grid[k] - truth[k]).squaredNorm(), from_edges += refined[k];
    const double rms_edges = std::sqrt(se / grid.size());
    std::printf(
        "[ figure ] corner RMS (from the board's edges vs ground truth, 64 spp, %s rig): %.4f px, %d of %zu "
        "corners from edges\n",
        misaligned ? "misaligned" : "aligned", rms_edges, from_edges, grid.size());
    EXPECT_EQ(from_edges, static_cast<int>(grid.size()));
    EXPECT_LE(rms_edges, 0.05) << (misaligned ? "misaligned" : "aligned");
    EXPECT_LT(rms_edges, rms);
  }
}

TEST(Render, RangePointAndNormalChannelsOfAPlaneAreAnalytic) {
  const SceneConfig cfg = BoardScene(false);
  const RayScene scene(cfg.description);
  const auto corners = scenes::BoardCornerTruth(scene, cfg.boards[0], 0);
  raytrace::RenderOptions ro;
  ro.samples = 1;
  ro.region = CornerRegion(corners, 10);
  const raytrace::Frame f = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  const auto& unit = scene.description().units[0];
  const auto& board = cfg.boards[0];
  const Vec3d n = board.world_from_board.Rotate(Vec3d(0, 0, 1)), c = board.world_from_board.translation;
  int checked = 0;
  double worst_rel = 0, worst_point = 0, worst_normal = 0;
  for (int y = ro.region.y0; y < ro.region.y1; ++y)
    for (int x = ro.region.x0; x < ro.region.x1; ++x) {
      const float* g = &f.truth.data[(static_cast<size_t>(y) * f.width + x) * raytrace::GroundTruth::kChannels];
      if (static_cast<int>(g[7]) != board.object_id) continue;
      Vec3d M, d;
      ASSERT_TRUE(unit.rig.RayFromImg(Vec2d(x, y), &M, &d));
      const Vec3d o = unit.world_from_mirror * M, dw = unit.world_from_mirror.Rotate(d);
      const Vec3d X = o + ((c - o).dot(n) / dw.dot(n)) * dw;
      const double range = (X - unit.world_from_mirror.translation).norm();
      worst_rel = std::max(worst_rel, std::abs(g[0] - range) / range);
      worst_point = std::max(worst_point, (Vec3d(g[1], g[2], g[3]) - X).norm());
      const Vec3d facing = dw.dot(n) < 0 ? n : Vec3d(-n);  // the normal channel faces the ray
      worst_normal = std::max(worst_normal, (Vec3d(g[4], g[5], g[6]) - facing).norm());
      EXPECT_EQ(g[8], 1.0f);
      ++checked;
    }
  EXPECT_GT(checked, 2000);
  EXPECT_LT(worst_rel, 1e-6);
  EXPECT_LT(worst_point, 1e-6);
  EXPECT_LT(worst_normal, 1e-6);
}

TEST(Render, MirrorMaskIsTheCoreMask) {
  const SceneConfig cfg = BoardScene(true);
  const RayScene scene(cfg.description);
  const auto& rig = scene.description().units[0].rig;
  raytrace::RenderOptions ro;
  ro.samples = 1;
  ro.region = {0, 1096, rig.camera.width, 1104};  // a band through the centre: rim, annulus, camera reflection
  const raytrace::Frame f = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  int agree = 0, total = 0, seen = 0;
  for (int y = ro.region.y0; y < ro.region.y1; ++y)
    for (int x = 0; x < f.width; ++x) {
      const float mask = f.truth.data[(static_cast<size_t>(y) * f.width + x) * raytrace::GroundTruth::kChannels + 8];
      const bool core = rig.SeesMirror(Vec2d(x, y));
      agree += (mask == 1.0f) == core;

      seen += core;
      ++total;
    }
  EXPECT_EQ(agree, total);
  EXPECT_GT(seen, total / 2);
  EXPECT_LT(seen, total);
}

// Sum of squared differences between neighbouring 4 x 4 block means of the red channel: falls when an image
// blurs, and the block means keep the Monte Carlo noise of lens and time sampling out of it.
double GradientEnergy(const raytrace::Frame& f, const raytrace::RenderOptions::Region& r) {
  const int bw = (r.x1 - r.x0) / 4, bh = (r.y1 - r.y0) / 4;
  std::vector<double> m(static_cast<size_t>(bw) * bh, 0.0);
  for (int by = 0; by < bh; ++by)
    for (int bx = 0; bx < bw; ++bx)
      for (int k = 0; k < 16; ++k)
        m[static_cast<size_t>(by) * bw + bx] +=
            f.rgb[3 * (static_cast<size_t>(r.y0 + 4 * by + k / 4) * f.width + r.x0 + 4 * bx + k % 4)] / 16.0;
  double e = 0;
  for (int by = 0; by + 1 < bh; ++by)
    for (int bx = 0; bx + 1 < bw; ++bx) {
      const size_t p = static_cast<size_t>(by) * bw + bx;
      e += std::pow(m[p + 1] - m[p], 2) + std::pow(m[p + bw] - m[p], 2);
    }
  return e;
}

TEST(Render, ThinLensDefocusAndMotionBlurSoftenTheImage) {
  SceneConfig cfg = BoardScene(false);
  // The board alone against the sky, so the measure sees only its edges.
  cfg.description.rects = {cfg.description.rects[cfg.boards[0].rect_index]};
  cfg.boards[0].rect_index = 0;
  const RayScene still(cfg.description);
  const auto corners = scenes::BoardCornerTruth(still, cfg.boards[0], 0);
  raytrace::RenderOptions ro;
  ro.samples = 36;
  ro.ground_truth = false;
  ro.region = CornerRegion(corners, 5);
  const auto sharp = raytrace::Render(still, raytrace::ViewCamera::Unit(0), ro);
  const double e_sharp = GradientEnergy(sharp, ro.region);
  // A wide aperture focused far from the mirror's virtual image blurs; focused on it, it barely does.
  ro.lens_radius = 0.002;
  ro.focus_distance = 1.0;
  const double e_defocus = GradientEnergy(raytrace::Render(still, raytrace::ViewCamera::Unit(0), ro), ro.region);
  ro.focus_distance = 0.135;
  const double e_focused = GradientEnergy(raytrace::Render(still, raytrace::ViewCamera::Unit(0), ro), ro.region);
  EXPECT_LT(e_defocus, 0.6 * e_sharp);
  EXPECT_GT(e_focused, 2 * e_defocus);
  // Motion blur is the time average: a unit turning about its axis during the exposure renders as the mean of
  // still frames of the unit at instants spread over the exposure.
  ro.lens_radius = 0;
  const double omega = 20 * kDeg, exposure = 0.05;
  cfg.description.units[0].angular_velocity = Vec3d(0, 0, omega);
  const RayScene turning(cfg.description);
  ro.exposure_time = exposure;
  ro.samples = 64;
  const auto blurred = raytrace::Render(turning, raytrace::ViewCamera::Unit(0), ro);
  ro.exposure_time = 0;
  ro.samples = 16;
  std::vector<double> mean(blurred.rgb.size(), 0.0);
  const int instants = 16;
  for (int k = 0; k < instants; ++k) {
    SceneConfig at = cfg;
    at.description.units[0].world_from_mirror =
        cfg.description.units[0].WorldFromMirrorAt((k + 0.5) * exposure / instants);
    at.description.units[0].angular_velocity = Vec3d::Zero();
    const auto f = raytrace::Render(RayScene(at.description), raytrace::ViewCamera::Unit(0), ro);
    for (size_t i = 0; i < mean.size(); ++i) mean[i] += f.rgb[i] / instants;
  }
  double to_mean = 0, to_sharp = 0;
  for (size_t i = 0; i < mean.size(); ++i) {
    to_mean += std::abs(blurred.rgb[i] - mean[i]);
    to_sharp += std::abs(blurred.rgb[i] - sharp.rgb[i]);
  }
  EXPECT_LT(to_mean, 0.25 * to_sharp) << "the blurred frame is the time average of still frames";
  ro.samples = 36;
  const auto no_exposure = raytrace::Render(turning, raytrace::ViewCamera::Unit(0), ro);
  EXPECT_EQ(no_exposure.rgb, sharp.rgb) << "zero exposure is the still frame";
}

TEST(Sensor, BayerNoiseAndVignettingDoWhatTheySay) {
  raytrace::Frame f;
  f.width = 64, f.height = 48;
  f.rgb.resize(static_cast<size_t>(f.width) * f.height * 3);
  for (size_t i = 0; i < f.rgb.size(); i += 3) f.rgb[i] = 0.8f, f.rgb[i + 1] = 0.4f, f.rgb[i + 2] = 0.2f;
  raytrace::SensorOptions s;
  s.bayer = true;
  int ch = 0;
  auto out = raytrace::ApplySensor(f, s, 1, &ch);
  ASSERT_EQ(ch, 1);
  EXPECT_FLOAT_EQ(out[0], 0.8f);            // R at (0, 0)
  EXPECT_FLOAT_EQ(out[1], 0.4f);            // G at (1, 0)
  EXPECT_FLOAT_EQ(out[f.width], 0.4f);      // G at (0, 1)
  EXPECT_FLOAT_EQ(out[f.width + 1], 0.2f);  // B at (1, 1)
  // Shot + read noise: the spread matches the electron statistics; the seed makes it repeatable.
  s = {};
  s.full_well = 10000, s.read_noise = 5;
  const auto a = raytrace::ApplySensor(f, s, 7, &ch), b = raytrace::ApplySensor(f, s, 7, &ch),
             c = raytrace::ApplySensor(f, s, 8, &ch);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  double mean = 0, var = 0;
  const size_t n = a.size() / 3;
  for (size_t i = 0; i < n; ++i) mean += a[3 * i];
  mean /= n;
  for (size_t i = 0; i < n; ++i) var += std::pow(a[3 * i] - mean, 2);
  var /= n - 1;
  const double expected_sigma = std::sqrt(0.8 * 10000 + 25) / 10000;
  EXPECT_NEAR(mean, 0.8, 4 * expected_sigma / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(var), expected_sigma, 0.1 * expected_sigma);
  // The deviates are Gaussian, not just of the right spread: the fractions beyond 1, 2 and 3 sigma.
  for (const auto& [z, fraction] : {std::pair{1.0, 0.3173}, {2.0, 0.0455}, {3.0, 0.0027}}) {
    size_t beyond = 0;
    for (size_t i = 0; i < n; ++i) beyond += std::abs(a[3 * i] - 0.8) > z * expected_sigma;
    EXPECT_NEAR(static_cast<double>(beyond) / n, fraction, 4 * std::sqrt(fraction * (1 - fraction) / n)) << z;
  }
  // Dark scenes (below 20 electrons, the Gaussian regime): Poisson counts, mean and variance e, 2.5 electrons
  // without read noise (whole counts, none with probability exp(-e)); 15 electrons with read noise of 2 (the
  // variance grows by its square; zero, where counts would be clipped, is 3.4 sigma away).
  raytrace::Frame dark;
  dark.width = 256, dark.height = 128;
  s = {};
  s.full_well = 10000;
  for (const auto& [e, read] : {std::pair{2.5, 0.0}, {15.0, 2.0}}) {
    dark.rgb.assign(static_cast<size_t>(dark.width) * dark.height * 3, static_cast<float>(e / 10000));
    s.read_noise = read;
    const auto d = raytrace::ApplySensor(dark, s, 3, &ch);
    double m = 0, m2 = 0, whole = 0, zero = 0;
    for (const float value : d) {
      const double count = value * 10000.0;
      m += count, m2 += count * count;
      whole += std::abs(count - std::round(count)) < 1e-3;
      zero += count < 0.5;
    }
    const double N = static_cast<double>(d.size());
    m /= N;
    const double variance = m2 / N - m * m, expected = e + read * read;
    EXPECT_NEAR(m, e, 4 * std::sqrt(expected / N)) << e;
    EXPECT_NEAR(variance, expected, 5 * std::sqrt(2.0 / N) * expected) << e;
    if (read == 0) {
      EXPECT_EQ(whole, N) << "Poisson counts are whole electrons";
      EXPECT_NEAR(zero / N, std::exp(-e), 4 * std::sqrt(std::exp(-e) / N));
    }
  }
  // Vignetting: the corner keeps 1 - v of the centre.
  s = {};
  s.vignetting = 0.3;
  const auto v = raytrace::ApplySensor(f, s, 1, &ch);
  EXPECT_NEAR(v[0] / 0.8, 0.7, 1e-5);
  EXPECT_NEAR(v[3 * (static_cast<size_t>(f.height / 2) * f.width + f.width / 2)] / 0.8, 1.0, 0.01);
}

TEST(Boards, ArucoTextureMatchesTheCornerTruth) {
  scenes::BoardSpec spec;
  spec.kind = scenes::BoardSpec::Kind::kAruco;
  spec.markers_x = 4, spec.markers_y = 3, spec.marker_length = 0.2, spec.marker_separation = 0.05, spec.margin = 0.03;
  const raytrace::Rect rect = scenes::MakeBoardRect(spec, Rigid3d(), 4);
  const auto& tex = *rect.front.image;
  cv::Mat img(tex.height, tex.width, CV_8U);
  for (int y = 0; y < tex.height; ++y)
    for (int x = 0; x < tex.width; ++x)
      img.at<uint8_t>(y, x) =
          static_cast<uint8_t>(std::lround(255 * tex.pixels[3 * (static_cast<size_t>(y) * tex.width + x)]));
  std::vector<std::vector<cv::Point2f>> found;
  std::vector<int> ids;
  cv::aruco::detectMarkers(img, cv::aruco::getPredefinedDictionary(cv::aruco::DICT_6X6_250), found, ids);
  ASSERT_EQ(ids.size(), 12u);
  std::map<int, Vec2d> truth;
  for (const auto& [id, xy] : spec.Corners()) truth[id] = xy;
  double worst = 0;
  for (size_t m = 0; m < ids.size(); ++m)
    for (int k = 0; k < 4; ++k) {
      const Vec2d xy = truth.at(4 * ids[m] + k);
      const double u = (xy.x() / spec.Width() + 0.5) * tex.width - 0.5,
                   v = (0.5 - xy.y() / spec.Height()) * tex.height - 0.5;
      worst = std::max(worst, std::hypot(found[m][k].x - u, found[m][k].y - v));
    }
  EXPECT_LT(worst, 1.0) << "texture pixels";
}

TEST(SceneConfig, RejectsBadInput) {
  const std::string unit =
      "units:\n  - mirror: {a: 0.048, b: 0.044, rim_diameter: 0.080}\n"
      "    camera: {focal_length: 0.016, pixel_pitch: 4.54e-6, width: 2750, height: 2200, lens_aperture: 0.020}\n"
      "    pose: {position: [0, 0, 1.3]}\n";
  const auto expect = [&](const std::string& text, const std::string& needle) {
    try {
      scenes::ParseSceneConfig(text, "bad.yaml", ".");
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.yaml"), std::string::npos) << e.what();
    }
  };
  EXPECT_NO_THROW(scenes::ParseSceneConfig(unit, "ok.yaml", "."));
  expect(unit + "lights: []\n", "unknown key 'lights'");
  expect(unit +
             "objects:\n  - {type: plane, pose: {position: [1, 0, 1]}, size: [1, 1], texture: {image: {path: nope.png, "
             "width: 1, height: 1}}}\n",
         "texture file not found");
  expect(unit + "objects:\n  - {type: sphere}\n", "unknown object type 'sphere'");
  expect(unit + "render: {samples: 0}\n", "samples");
  expect(unit + "render: {sensor: {bit_depth: 12}}\n", "bit_depth");
  std::string f0 = unit;
  f0.replace(f0.find("focal_length: 0.016"), 19, "focal_length: 0.0");
  expect(f0, "must be positive");
  expect(std::string(unit).insert(unit.find("    pose"), "    misalignment: {height_error: -0.2}\n"),
         "inside the mirror");
  expect(unit +
             "objects:\n  - {type: plane, pose: {position: [1, 0, 1], look_at: [2e4, 0, 1]}, size: [1, 1], "
             "texture: {solid: [1, 1, 1]}}\n",
         "from the world origin");
  expect(unit +
             "objects:\n  - {type: plane, pose: {position: [1, 0, 1]}, size: [1, 1], "
             "texture: {checker: {squares: [0, 3], square: 0.1}}}\n",
         "at least 1 x 1 squares");
  // Objects that pass through a unit, or enclose it: a wall through its axis, the ground between its camera and
  // its mirror (F1 1.3 m up, the camera 0.13 m below), a box around it, a box cutting its camera body. A box
  // beside it and the ground below it are fine.
  const auto object = [&](const std::string& o) { return unit + "objects:\n  - " + o + "\n"; };
  const std::string solid = "texture: {solid: [1, 1, 1]}}";
  expect(object("{type: plane, name: wall, pose: {position: [0, 0, 1.3], rotation_deg: [0, 90, 0]}, size: [2, 2], " +
                solid),
         "object 'wall' passes through unit 'unit0'");
  expect(object("{type: ground, name: floor, height: 1.22, " + solid), "object 'floor' passes through unit 'unit0'");
  expect(object("{type: box, name: crate, pose: {position: [0, 0, 0]}, size: [1, 1, 2], " + solid),
         "unit 'unit0' is inside box 'crate'");
  expect(object("{type: box, name: crate, pose: {position: [0.2, 0, 0]}, size: [0.5, 0.5, 1.1], " + solid),
         "object 'crate' passes through unit 'unit0'");
  EXPECT_NO_THROW(scenes::ParseSceneConfig(
      object("{type: box, name: crate, pose: {position: [0.4, 0, 0]}, size: [0.5, 0.5, 2], " + solid), "ok.yaml", "."));
  EXPECT_NO_THROW(scenes::ParseSceneConfig(object("{type: ground, name: floor, " + solid), "ok.yaml", "."));
}

TEST(RayScene, RejectsAWorldBeyondSinglePrecision) {
  // Embree traces in single precision: parts beyond kWorldExtent (or not finite) are refused before any Embree
  // object exists, with the part named. (A mirror with a = 1e300 put the camera at -2e300 and Embree aborted.)
  const auto base = scenes::ParseSceneConfig(
      "units:\n  - mirror: {a: 0.048, b: 0.044, rim_diameter: 0.080}\n"
      "    camera: {focal_length: 0.016, pixel_pitch: 4.54e-6, width: 275, height: 220, lens_aperture: 0.020}\n"
      "    pose: {position: [0, 0, 1.3]}\n"
      "objects:\n  - {type: plane, name: wall, pose: {position: [3, 0, 1], look_at: [0, 0, 1]}, size: [2, 2], "
      "texture: {solid: [1, 1, 1]}}\n",
      "ok.yaml", ".");
  EXPECT_NO_THROW(raytrace::RayScene scene(base.description));
  const auto expect = [](raytrace::SceneDescription d, const std::string& needle) {
    try {
      raytrace::RayScene scene(std::move(d));
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what(); }
  };
  raytrace::SceneDescription wide = base.description;
  wide.rects[0].width = 3 * raytrace::kWorldExtent;  // its corners reach past the extent, its centre does not
  expect(wide, "'wall'");
  raytrace::SceneDescription big_mirror = base.description;
  big_mirror.units[0].rig.mirror.a = 1e300;
  expect(big_mirror, "unit unit0");
  raytrace::SceneDescription nan_pose = base.description;
  nan_pose.units[0].world_from_mirror.translation.x() = std::nan("");
  expect(nan_pose, "unit unit0");
}

TEST(Render, ThinLensAndMotionBlurRaysAreTheCoresGeometry) {
  // The vectorised thin-lens and motion-blur rays (SampleRays, as RenderInto makes them) against the same rays
  // built from the core, sample by sample: the pinhole bearing (CamFromImg), the ray from the aperture point
  // towards the bearing's point on the plane in focus, the exact mirror (ReflectCameraRay), the unit's pose at
  // the sample's time (WorldFromMirrorAt). A misaligned rig on a unit moving and turning about a tilted axis;
  // samples over the whole image (on the mirror and past the rim), aperture points over the unit disc, times over
  // the exposure; with and without the lens, with and without the motion, with and without lens distortion.
  SceneConfig cfg = BoardScene(true);
  auto& u0 = cfg.description.units[0];
  const RayScene still(cfg.description);
  SceneConfig distorted_cfg = cfg;
  auto& dist = distorted_cfg.description.units[0].rig.camera.distortion;
  dist.k1 = -0.08, dist.k2 = 0.02, dist.p1 = 2e-4, dist.p2 = -1e-4;
  const RayScene distorted(distorted_cfg.description);
  u0.velocity = Vec3d(1.5, -0.4, 0.2);
  u0.angular_velocity = Vec3d(0.3, -0.2, 0.9);
  const RayScene moving(cfg.description);
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> U(0, 1);
  const int n = 256;
  const int width = u0.rig.camera.width, height = u0.rig.camera.height;
  std::vector<double> us(n), vs(n), dx(n), dy(n), tau(n);
  for (int i = 0; i < n; ++i) {
    us[i] = -0.5 + width * U(rng), vs[i] = -0.5 + height * U(rng);
    const double r = std::sqrt(U(rng)), phi = 2 * M_PI * U(rng);
    dx[i] = r * std::cos(phi), dy[i] = r * std::sin(phi);
    tau[i] = 0.05 * U(rng);
  }
  tau[0] = 0;
  for (const double lens : {0.0, 0.003}) {
    for (const int kind : {0, 1, 2}) {  // still, moving, still with lens distortion
      const bool blur = kind == 1;
      const RayScene& scene = kind == 0 ? still : kind == 1 ? moving : distorted;
      const auto& unit = scene.description().units[0];
      const auto& cam = unit.rig.camera;
      raytrace::RenderOptions ro;
      ro.lens_radius = lens;
      ro.focus_distance = 0.8;
      ro.exposure_time = blur ? 0.05 : 0.0;
      raytrace::RayBatch b;
      raytrace::SampleRays(scene, raytrace::ViewCamera::Unit(0), ro, n, us.data(), vs.data(), dx.data(), dy.data(),
                           blur ? tau.data() : nullptr, &b);
      ASSERT_EQ(b.n, n);
      const Rigid3d mirror_from_cam = unit.rig.cam_from_mirror.Inverse();
      int on_mirror = 0, past_rim = 0, rings = 0;
      double worst_o = 0, worst_d = 0;
      for (int i = 0; i < n; ++i) {
        Vec3d bearing;
        ASSERT_TRUE(cam.CamFromImg(Vec2d(us[i], vs[i]), &bearing));
        const Vec3d origin_cam(lens * dx[i], lens * dy[i], 0);
        const Vec3d dir_cam =
            lens > 0 ? Vec3d((bearing * (ro.focus_distance / bearing.z()) - origin_cam).normalized()) : bearing;
        const Rigid3d world_from_mirror = unit.WorldFromMirrorAt(blur ? tau[i] : 0.0);
        Vec3d M, d, o_world, d_world;
        const bool hit =
            unit.rig.ReflectCameraRay(mirror_from_cam * origin_cam, mirror_from_cam.Rotate(dir_cam), &M, &d);
        if (hit) {
          o_world = world_from_mirror * M, d_world = world_from_mirror.Rotate(d);
          ++on_mirror;
        } else {
          const Rigid3d world_from_cam = world_from_mirror * mirror_from_cam;
          o_world = world_from_cam * origin_cam, d_world = world_from_cam.Rotate(dir_cam);
          ++past_rim;
          // The unit's own straight ray (its mirror and lens face masked off), ended on its mount ring: the
          // annulus between the rim and the ring's outer radius in the rim plane, met in the unit's frame.
          const Vec3d om = mirror_from_cam * origin_cam, vm = mirror_from_cam.Rotate(dir_cam);
          const double t = (unit.rig.mirror.RimZ() - om.z()) / vm.z();
          const double r = (om + t * vm).head<2>().norm();
          const bool ring = vm.z() != 0 && t > 1e-5 && r >= unit.rig.mirror.RimRadius() && r <= unit.mount_outer_radius;
          EXPECT_EQ(b.from_camera[i], 0) << "sample " << i;
          EXPECT_NEAR(b.mount_t[i], ring ? t : 0.0, 1e-12) << "sample " << i;
          rings += ring;
        }
        if (hit) { EXPECT_EQ(b.from_camera[i], -1) << "sample " << i; }
        ASSERT_EQ(b.from_mirror[i], hit ? 0 : -1) << "sample " << i;
        EXPECT_EQ(b.valid[i], 1);
        EXPECT_EQ(b.tnear[i], 1e-5f);
        worst_o = std::max(worst_o, (Vec3d(b.ox[i], b.oy[i], b.oz[i]) - o_world).norm());
        worst_d = std::max(worst_d, (Vec3d(b.dx[i], b.dy[i], b.dz[i]) - d_world).norm());
      }
      EXPECT_LT(worst_o, 1e-12) << "lens " << lens << " kind " << kind;
      EXPECT_LT(worst_d, 1e-12) << "lens " << lens << " kind " << kind;
      EXPECT_GT(on_mirror, 50);
      EXPECT_GT(past_rim, 50);
      EXPECT_GT(rings, 20);
    }
  }
  // A pinhole view through a thin lens (no mirror), with and without lens distortion: from the aperture point
  // towards the pinhole ray's point on the plane in focus, mapped by world_from_cam.
  const Rigid3d world_from_cam(QuaternionFromAngleAxis<double>(Vec3d(0.3, -1.2, 0.4)), Vec3d(0.5, -0.2, 1.1));
  std::vector<double> pu(n), pv(n);
  for (int i = 0; i < n; ++i) pu[i] = us[i] * 640 / width, pv[i] = vs[i] * 480 / height;
  for (const bool with_distortion : {false, true}) {
    PinholeCamera<double> pin = PinholeCamera<double>::FromPhysical(0.008, 5e-6, 640, 480);
    if (with_distortion) pin.distortion.k1 = -0.1, pin.distortion.p2 = 3e-4;
    raytrace::RenderOptions ro;
    ro.lens_radius = 0.004;
    ro.focus_distance = 2.5;
    raytrace::RayBatch b;
    raytrace::SampleRays(still, raytrace::ViewCamera::Pinhole(pin, world_from_cam), ro, n, pu.data(), pv.data(),
                         dx.data(), dy.data(), nullptr, &b);
    double worst = 0;
    for (int i = 0; i < n; ++i) {
      Vec3d bearing;
      ASSERT_TRUE(pin.CamFromImg(Vec2d(pu[i], pv[i]), &bearing));
      const Vec3d origin_cam(ro.lens_radius * dx[i], ro.lens_radius * dy[i], 0);
      const Vec3d dir_cam = (bearing * (ro.focus_distance / bearing.z()) - origin_cam).normalized();
      EXPECT_EQ(b.from_mirror[i], -1);
      EXPECT_EQ(b.valid[i], 1);
      worst = std::max(worst, (Vec3d(b.ox[i], b.oy[i], b.oz[i]) - world_from_cam * origin_cam).norm());
      worst = std::max(worst, (Vec3d(b.dx[i], b.dy[i], b.dz[i]) - world_from_cam.Rotate(dir_cam)).norm());
    }
    EXPECT_LT(worst, 1e-12) << (with_distortion ? "with" : "without") << " distortion";
  }
  // Bad input: more points than a batch holds, an aperture point without its second coordinate.
  raytrace::RayBatch b;
  std::vector<double> many(raytrace::RayBatch::kMax + 1, 100.0);
  EXPECT_THROW(raytrace::SampleRays(still, raytrace::ViewCamera::Unit(0), {}, static_cast<int>(many.size()),
                                    many.data(), many.data(), nullptr, nullptr, nullptr, &b),
               Error);
  EXPECT_THROW(raytrace::SampleRays(still, raytrace::ViewCamera::Unit(0), {}, 1, many.data(), many.data(), many.data(),
                                    nullptr, nullptr, &b),
               Error);
}

TEST(Render, PastTheRimTheCameraSeesTheMountNotItsOwnLens) {
  // A camera ray that misses the mirror leaves the camera's own lens face; it used to meet that face again at
  // t = 0 (float rounding), which painted everything past the rim in the body's colour with the body's id.
  // Both ray paths (the batched pinhole path and the thin-lens path) must see the mount ring; so must a unit that
  // moves and turns during the exposure (its mount moves with it: up to 11 cm in this exposure, which once left
  // the rays of the moved camera passing beside the ring where it stood at time 0).
  SceneConfig cfg = SmallBoardScene(25);
  const RayScene scene(cfg.description);
  cfg.description.units[0].velocity = Vec3d(5, 2, 0);
  cfg.description.units[0].angular_velocity = Vec3d(0, 0, 30 * kDeg);
  const RayScene moving_scene(cfg.description);
  const auto& unit = scene.description().units[0];
  for (const double lens : {0.0, 1e-4, 2e-4}) {
    const bool moving = lens > 1.5e-4;
    raytrace::RenderOptions ro;
    ro.samples = 4;
    ro.lens_radius = lens;
    ro.exposure_time = moving ? 0.02 : 0.0;
    const raytrace::Frame f = raytrace::Render(moving ? moving_scene : scene, raytrace::ViewCamera::Unit(0), ro);
    int past_rim = 0;
    for (const auto& [x, y] : {std::pair{0, 0}, {109, 0}, {0, 87}, {109, 87}}) {
      Vec3d M, d;
      ASSERT_FALSE(unit.rig.RayFromImg(Vec2d(x, y), &M, &d)) << "the corner must lie past the rim";
      ++past_rim;
      const size_t p = static_cast<size_t>(y) * f.width + x;
      for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(f.rgb[3 * p + c], unit.mount_colour[c]) << "lens " << lens;
      // The ground truth (pixel centre, no lens): the mount, beyond the camera, not the lens face.
      EXPECT_EQ(f.truth.data[p * raytrace::GroundTruth::kChannels + 7], raytrace::kMountId);
      EXPECT_EQ(f.truth.data[p * raytrace::GroundTruth::kChannels + 8], 0.0f) << "not a mirror pixel";
      // Its point lies on the ring (the rim plane, between the rim and the ring's outer radius), on the pixel's
      // straight camera ray, at the recorded range from the viewpoint; its normal is the mirror axis, facing the
      // camera.
      const float* g = &f.truth.data[p * raytrace::GroundTruth::kChannels];
      const Vec3d P(g[1], g[2], g[3]), N(g[4], g[5], g[6]);
      const Vec3d Pm = unit.world_from_mirror.Inverse() * P;
      EXPECT_NEAR(Pm.z(), unit.rig.mirror.RimZ(), 1e-6);
      EXPECT_GE(Pm.head<2>().norm(), unit.rig.mirror.RimRadius() - 1e-6);
      EXPECT_LE(Pm.head<2>().norm(), unit.mount_outer_radius + 1e-6);
      Vec2d uv;
      ASSERT_TRUE(unit.rig.camera.ImgFromCam(unit.rig.cam_from_mirror * Pm, &uv));
      EXPECT_NEAR(uv.x(), x, 1e-3);
      EXPECT_NEAR(uv.y(), y, 1e-3);
      EXPECT_NEAR(g[0], (P - unit.world_from_mirror.translation).norm(), 1e-6);
      EXPECT_NEAR(std::abs(N.dot(unit.world_from_mirror.Rotate(Vec3d(0, 0, 1)))), 1.0, 1e-6);
      EXPECT_GT(N.dot(unit.world_from_mirror * unit.rig.CameraCentre() - P), 0) << "the normal faces the camera";
    }
    EXPECT_EQ(past_rim, 4);
  }
}

TEST(Render, UnderMotionBlurTheCamerasOwnReflectionStaysSharp) {
  // The camera body, lens face, mirror and mount ring move with the unit, so a sample at time tau must meet them
  // where they are at tau: the camera's reflection at the image centre is the same under any motion. (They used
  // to stay where they stood at time 0: at 10 cm of travel the reflected rays of later samples passed beside
  // the body and saw the floor.) The ground truth is at time 0 and does not depend on the motion.
  SceneConfig cfg = SmallBoardScene(5);
  const RayScene still(cfg.description);
  cfg.description.units[0].velocity = Vec3d(5, 2, 0.5);
  cfg.description.units[0].angular_velocity = Vec3d(0.2, -0.1, 0.6);
  const RayScene moving(cfg.description);
  const raytrace::CatadioptricUnit& unit = still.description().units[0];
  raytrace::RenderOptions ro;
  ro.samples = 16;
  const raytrace::Frame s = raytrace::Render(still, raytrace::ViewCamera::Unit(0), ro);
  ro.exposure_time = 0.02;
  const raytrace::Frame m = raytrace::Render(moving, raytrace::ViewCamera::Unit(0), ro);
  constexpr int C = raytrace::GroundTruth::kChannels;
  const auto id_at = [&](const raytrace::Frame& f, int x, int y) {
    return static_cast<int>(f.truth.data[(static_cast<size_t>(y) * f.width + x) * C + 7]);
  };
  // Pixels whose samples all see the body in the mirror: the pixel and its neighbours are body pixels.
  int body = 0, differ = 0;
  double worst = 0;
  for (int y = 1; y + 1 < s.height; ++y) {
    for (int x = 1; x + 1 < s.width; ++x) {
      // (A reflection: the mirror point M is set; the mask channel is 0 where the mirror shows the camera.)
      bool inside = s.truth.data[(static_cast<size_t>(y) * s.width + x) * C + 11] != 0.0f;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) inside = inside && id_at(s, x + dx, y + dy) == raytrace::kCameraBodyId;
      if (!inside) continue;
      ++body;
      const size_t p = static_cast<size_t>(y) * s.width + x;
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(s.rgb[3 * p + c], unit.body_colour[c], 1e-6);
        worst = std::max(worst, std::abs(static_cast<double>(m.rgb[3 * p + c]) - unit.body_colour[c]));
      }
      differ += std::abs(m.rgb[3 * p] - unit.body_colour[0]) > 1e-6 ? 1 : 0;
    }
  }
  EXPECT_GT(body, 100) << "the camera's reflection covers a disc at the image centre";
  EXPECT_EQ(differ, 0) << "of " << body << " pixels of the camera's reflection; worst colour error " << worst;
  // Time-0 ground truth: the same as the still unit's wherever both see the same object (all but a few
  // silhouette pixels, where Embree meets the moving unit's parts through its instance transform in single
  // precision).
  int same_id = 0;
  size_t pixels = static_cast<size_t>(s.width) * s.height, channels_differ = 0;
  for (size_t p = 0; p < pixels; ++p) {
    if (s.truth.data[p * C + 7] != m.truth.data[p * C + 7]) continue;
    ++same_id;
    for (int c = 0; c < C; ++c) channels_differ += s.truth.data[p * C + c] != m.truth.data[p * C + c] ? 1 : 0;
  }
  EXPECT_GE(same_id, static_cast<int>(pixels) - 5);
  EXPECT_EQ(channels_differ, 0u);

  // A stereo rig moving as one (both units at the same velocity): each unit sees the other's mirror, mount and
  // body at rest relative to it, so they too stay sharp in its blurred frame.
  SceneConfig pair = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_stereo.yaml");
  for (auto& u : pair.description.units)
    u.rig.camera = PinholeCamera<double>::FromPhysical(0.016, 4.54e-6 * 5, 550, 440);
  const RayScene pair_still(pair.description);
  for (auto& u : pair.description.units) u.velocity = Vec3d(3, 1, 0.2);
  const RayScene pair_moving(pair.description);
  const Vec3d other = pair_still.description().units[1].world_from_mirror.translation;
  ro.exposure_time = 0;
  const raytrace::Frame ps = raytrace::Render(pair_still, raytrace::ViewCamera::Unit(0), ro);
  ro.exposure_time = 0.02;
  const raytrace::Frame pm = raytrace::Render(pair_moving, raytrace::ViewCamera::Unit(0), ro);
  int seen = 0, changed = 0;
  for (int y = 1; y + 1 < ps.height; ++y) {
    for (int x = 1; x + 1 < ps.width; ++x) {
      const size_t p = static_cast<size_t>(y) * ps.width + x;
      const float* g = &ps.truth.data[p * C];
      const int id = static_cast<int>(g[7]);
      // The other unit's parts (within 0.2 m of its viewpoint), seen in the mirror, the neighbours alike.
      bool inside = (id == raytrace::kMountId || id == raytrace::kCameraBodyId || id == raytrace::kMirrorId) &&
                    g[11] != 0.0f && (Vec3d(g[1], g[2], g[3]) - other).norm() < 0.2;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) inside = inside && id_at(ps, x + dx, y + dy) == id;
      if (!inside) continue;
      ++seen;
      for (int c = 0; c < 3; ++c) changed += std::abs(pm.rgb[3 * p + c] - ps.rgb[3 * p + c]) > 1e-6 ? 1 : 0;
    }
  }
  EXPECT_GT(seen, 20) << "the left unit sees the right one";
  EXPECT_EQ(changed, 0) << "colour channels of " << seen << " pixels showing the other unit";
}

TEST(RayScene, AMovingUnitsOwnRaysMeetItsPartsWhereAStillUnitsDo) {
  // Rays leaving a moving unit's mirror meet its lens face, mount and camera body analytically in its mirror
  // frame (RayScene::OwnPartsInMirrorFrame); a still unit's meet them through Embree. At time 0 both must give
  // the same hits: rays at each face of the body box (from beside it), at the lens face and at the mount ring.
  SceneConfig cfg = SmallBoardScene(25);
  const RayScene still(cfg.description);
  cfg.description.units[0].velocity = Vec3d(2, 0, 0);
  const RayScene moving(cfg.description);
  ASSERT_TRUE(moving.OwnPartsInMirrorFrame(0));
  ASSERT_FALSE(still.OwnPartsInMirrorFrame(0));
  const raytrace::CatadioptricUnit& u = still.description().units[0];
  const Rigid3d world_from_cam = u.world_from_mirror * u.rig.cam_from_mirror.Inverse();
  const double h = 0.7 * u.rig.occluder_radius, L = u.body_length;
  // (origin, target) in the camera frame: the body's faces +x, -x, +y, -y and bottom, then the lens face and,
  // from the mirror frame, the mount ring from below.
  std::vector<std::pair<Vec3d, Vec3d>> cam_rays = {{Vec3d(3 * h, 0.2 * h, -0.4 * L), Vec3d(h, 0.1 * h, -0.5 * L)},
                                                   {Vec3d(-3 * h, -0.2 * h, -0.6 * L), Vec3d(-h, 0, -0.5 * L)},
                                                   {Vec3d(0.3 * h, 3 * h, -0.5 * L), Vec3d(0, h, -0.3 * L)},
                                                   {Vec3d(-0.1 * h, -3 * h, -0.2 * L), Vec3d(0.2 * h, -h, -0.7 * L)},
                                                   {Vec3d(0.1 * h, 0.2 * h, -3 * L), Vec3d(0, 0, -L)},
                                                   {Vec3d(0.2 * h, 0.1 * h, 0.05), Vec3d(0.3 * h, -0.2 * h, 0)}};
  raytrace::RayBatch b;
  const auto add = [&](const Vec3d& o_w, const Vec3d& target_w) {
    const int i = b.n++;
    const Vec3d d = (target_w - o_w).normalized();
    b.ox[i] = o_w.x(), b.oy[i] = o_w.y(), b.oz[i] = o_w.z(), b.dx[i] = d.x(), b.dy[i] = d.y(), b.dz[i] = d.z();
    b.tnear[i] = 1e-5f, b.from_mirror[i] = 0, b.from_camera[i] = -1, b.mount_t[i] = -1, b.valid[i] = 1;
  };
  for (const auto& [o, t] : cam_rays) add(world_from_cam * o, world_from_cam * t);
  const double zr = u.rig.mirror.RimZ(), rr = u.rig.mirror.RimRadius();
  add(u.world_from_mirror * Vec3d(0.5 * rr, 0, zr - 0.02), u.world_from_mirror * Vec3d(rr + 0.005, 0.002, zr));
  raytrace::HitBatch hs, hm;
  still.Geometry(b, &hs);
  moving.Geometry(b, &hm);
  const int expected_id[] = {raytrace::kCameraBodyId, raytrace::kCameraBodyId, raytrace::kCameraBodyId,
                             raytrace::kCameraBodyId, raytrace::kCameraBodyId, raytrace::kCameraBodyId,
                             raytrace::kMountId};
  for (int i = 0; i < b.n; ++i) {
    EXPECT_EQ(hs.object_id[i], expected_id[i]) << "ray " << i;
    EXPECT_EQ(hm.object_id[i], hs.object_id[i]) << "ray " << i;
    EXPECT_NEAR(hm.px[i], hs.px[i], 1e-9) << "ray " << i;
    EXPECT_NEAR(hm.py[i], hs.py[i], 1e-9) << "ray " << i;
    EXPECT_NEAR(hm.pz[i], hs.pz[i], 1e-9) << "ray " << i;
    EXPECT_NEAR(hm.nx[i], hs.nx[i], 1e-12) << "ray " << i;
    EXPECT_NEAR(hm.ny[i], hs.ny[i], 1e-12) << "ray " << i;
    EXPECT_NEAR(hm.nz[i], hs.nz[i], 1e-12) << "ray " << i;
  }
}

TEST(Render, AnExposureBeyondTheMotionHorizonIsRefused) {
  // A unit turning at 100 rad/s needs a time step per quarter turn: Embree's 129 steps cover about 2 s of it.
  SceneConfig cfg = SmallBoardScene(25);
  cfg.description.units[0].angular_velocity = Vec3d(0, 0, 100);
  const RayScene scene(cfg.description);
  EXPECT_NEAR(scene.MotionHorizon(), 128 * (M_PI / 2) / 100, 1e-12);
  raytrace::RenderOptions ro;
  ro.samples = 1;
  ro.ground_truth = false;
  ro.exposure_time = 3.0;
  try {
    raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
    ADD_FAILURE() << "an exposure beyond the horizon was rendered";
  } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find("exposure_time"), std::string::npos) << e.what(); }
  ro.exposure_time = 1.0;  // within it
  EXPECT_NO_THROW(raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro));
}

// Unit 0's camera in the world and the unit world direction of its ray through the image's corner pixel (0, 0)
// (with SmallBoardScene(25), a 110 x 88 image, the corners lie past the rim, on the mount ring).
bool CornerRay(const SceneConfig& cfg, Rigid3d* world_from_cam, Vec3d* dir) {
  const auto& unit = cfg.description.units[0];
  *world_from_cam = unit.world_from_mirror * unit.rig.cam_from_mirror.Inverse();
  Vec3d bearing;
  if (!unit.rig.camera.CamFromImg(Vec2d(0, 0), &bearing)) return false;
  *dir = world_from_cam->Rotate(bearing.normalized());
  return true;
}

TEST(Render, SomethingBetweenTheCameraAndItsMountIsSeenInFrontOfIt) {
  // A camera ray past the rim meets the mount ring analytically and goes to Embree only up to the ring: plates
  // placed on such rays, 2 cm in front of the camera and just in front of the ring, must still be seen (and the
  // ring elsewhere), on both ray paths (the pinhole samples and the thin-lens samples).
  SceneConfig cfg = SmallBoardScene(25);
  auto& unit_cfg = cfg.description.units[0];
  Rigid3d world_from_cam;
  Vec3d dir, bearing;
  ASSERT_TRUE(CornerRay(cfg, &world_from_cam, &dir));
  raytrace::Rect plate;
  plate.object_id = 77;
  // (Plate centres sit a little off the pixel's ray, so that ray does not run along the quad's diagonal, which
  // Embree's fast, non-robust quad test may miss.)
  const Rigid3d off_centre = Rigid3d::Translation(Vec3d(3e-4, 1e-4, 0));
  plate.world_from_rect =
      Rigid3d(Eigen::Quaterniond::FromTwoVectors(Vec3d::UnitZ(), -dir), world_from_cam.translation + 0.02 * dir) *
      off_centre;
  plate.width = plate.height = 0.004;
  plate.front.kind = raytrace::Texture::Kind::kSolid;
  plate.front.colour_a = {0.9f, 0.1f, 0.3f};
  plate.double_sided = true;
  // A second plate just in front of the ring (97 % of the way along the ray of the corner pixel (0, 87)): the
  // distance up to which such rays are traced must be measured along their unit direction.
  ASSERT_TRUE(unit_cfg.rig.camera.CamFromImg(Vec2d(0, 87), &bearing));
  const Rigid3d mirror_from_cam = unit_cfg.rig.cam_from_mirror.Inverse();
  const Vec3d v = mirror_from_cam.Rotate(bearing.normalized());
  const double to_ring = (unit_cfg.rig.mirror.RimZ() - mirror_from_cam.translation.z()) / v.z();
  ASSERT_GT(to_ring, 0.05);
  const Vec3d dir2 = world_from_cam.Rotate(bearing.normalized());
  raytrace::Rect near_ring = plate;
  near_ring.object_id = 78;
  near_ring.world_from_rect = Rigid3d(Eigen::Quaterniond::FromTwoVectors(Vec3d::UnitZ(), -dir2),
                                      world_from_cam.translation + 0.97 * to_ring * dir2) *
                              off_centre;
  near_ring.front.colour_a = {0.2f, 0.8f, 0.4f};
  // Without the plates nothing is in between: the camera rays past the rim skip Embree (RayScene::OwnMount).
  EXPECT_TRUE(RayScene(cfg.description).MountPathClear(0));
  cfg.description.rects.push_back(plate);
  cfg.description.rects.push_back(near_ring);
  const RayScene scene(cfg.description);
  EXPECT_FALSE(scene.MountPathClear(0));
  const auto& unit = scene.description().units[0];
  {
    // A ray through the exact centre of a rectangle runs along its quad's diagonal: still a hit (robust mode).
    SceneConfig centred = cfg;
    centred.description.rects.back().world_from_rect = near_ring.world_from_rect * off_centre.Inverse();
    const raytrace::Hit h = RayScene(centred.description).Trace(world_from_cam.translation, dir2, 1e-5);
    EXPECT_EQ(h.object_id, 78);
    EXPECT_NEAR(h.t, 0.97 * to_ring, 1e-9);
  }
  for (const double lens : {0.0, 1e-4}) {
    raytrace::RenderOptions ro;
    ro.samples = 4;
    ro.lens_radius = lens;
    const raytrace::Frame f = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
    const size_t corner = 0, far_corner = static_cast<size_t>(87) * f.width + 109;
    const size_t low_corner = static_cast<size_t>(87) * f.width;
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(f.rgb[3 * corner + c], plate.front.colour_a[c], 1e-6) << "lens " << lens;
      EXPECT_NEAR(f.rgb[3 * low_corner + c], near_ring.front.colour_a[c], 1e-6) << "lens " << lens;
      EXPECT_FLOAT_EQ(f.rgb[3 * far_corner + c], unit.mount_colour[c]) << "lens " << lens;
    }
    EXPECT_EQ(f.truth.data[corner * raytrace::GroundTruth::kChannels + 7], 77.0f);
    EXPECT_EQ(f.truth.data[low_corner * raytrace::GroundTruth::kChannels + 7], 78.0f);
    EXPECT_EQ(f.truth.data[far_corner * raytrace::GroundTruth::kChannels + 7], raytrace::kMountId);
    // With something in between, every ray goes to Embree (the straight ones only up to the ring).
    EXPECT_EQ(f.embree_rays, f.rays) << "lens " << lens;
  }
}

TEST(Render, SomethingAMovingUnitComesNearDuringTheExposureIsSeenInFrontOfItsMount) {
  // The unit moves at 2 m/s along x for 0.1 s. A still plate lies 11-30 cm to the side of its camera, outside the
  // region between camera and mount ring at time 0, but the image corner's straight ray (camera to ring) passes
  // through it after about half the exposure. The corner's samples must see it there: the time-0 decision that
  // nothing is in between (so those rays skip Embree) must not hold for the blurred frame.
  SceneConfig cfg = SmallBoardScene(25);
  auto& unit_cfg = cfg.description.units[0];
  Rigid3d world_from_cam;
  Vec3d dir;
  ASSERT_TRUE(CornerRay(cfg, &world_from_cam, &dir));
  const Vec3d c = world_from_cam.translation;
  ASSERT_GT(dir.z(), 0.5);                      // the unit stands upright: the corner's ray goes up to the ring
  const Vec3d at = c + (0.03 / dir.z()) * dir;  // the ray 3 cm above the camera
  ASSERT_LT(std::abs(at.x() - c.x()), 0.02);
  raytrace::Rect plate;  // horizontal, 3 cm above the camera, x from c.x + 0.11 to c.x + 0.31
  plate.object_id = 79;
  plate.world_from_rect = Rigid3d::Translation(Vec3d(c.x() + 0.21, at.y(), at.z()));
  plate.width = 0.2, plate.height = 0.1;
  plate.front.kind = raytrace::Texture::Kind::kSolid;
  plate.front.colour_a = {0.9f, 0.1f, 0.3f};
  plate.double_sided = true;
  cfg.description.rects.push_back(plate);
  unit_cfg.velocity = Vec3d(2, 0, 0);
  const RayScene scene(cfg.description);
  EXPECT_TRUE(scene.MountPathClear(0));               // at time 0 nothing is in between
  EXPECT_TRUE(scene.MountPathClearDuring(0, 0.002));  // nor within 4 mm of travel
  EXPECT_FALSE(scene.MountPathClearDuring(0, 0.1));
  raytrace::RenderOptions ro;
  ro.samples = 16;
  ro.exposure_time = 0.1;
  const raytrace::Frame f = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  // The corner's colour: (1 - w) mount + w plate, w the share of its samples' times past about 0.05 s.
  const raytrace::Rgb& mount = scene.description().units[0].mount_colour;
  const double w = (f.rgb[0] - mount[0]) / (plate.front.colour_a[0] - mount[0]);
  EXPECT_GT(w, 0.25) << "corner colour " << f.rgb[0] << " " << f.rgb[1] << " " << f.rgb[2];
  EXPECT_LT(w, 0.75);
  for (int ch = 1; ch < 3; ++ch)
    EXPECT_NEAR(f.rgb[ch], (1 - w) * mount[ch] + w * plate.front.colour_a[ch], 1e-4) << "channel " << ch;
  // Without motion the plate stays out of the way.
  ro.exposure_time = 0;
  const raytrace::Frame still = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  for (int ch = 0; ch < 3; ++ch) EXPECT_FLOAT_EQ(still.rgb[ch], mount[ch]);
  // A turn: at 2 rad/s about y through the viewpoint, the camera (13 cm below it) swings towards -x, 11 cm in
  // 0.5 s, into the same plate placed on that side.
  SceneConfig turning = cfg;
  turning.description.units[0].velocity = Vec3d::Zero();
  turning.description.units[0].angular_velocity = Vec3d(0, 2, 0);
  turning.description.rects.back().world_from_rect = Rigid3d::Translation(Vec3d(c.x() - 0.21, at.y(), at.z()));
  const RayScene turns(turning.description);
  EXPECT_TRUE(turns.MountPathClear(0));
  EXPECT_TRUE(turns.MountPathClearDuring(0, 0.01));
  EXPECT_FALSE(turns.MountPathClearDuring(0, 0.5));
}

TEST(Render, RaysEndingOnTheMountRingAreNotCountedAsEmbreeRays) {
  // Frame::embree_rays leaves out the camera rays past the rim that end on the unit's own mount ring without
  // Embree (nothing can lie in between). Pixels whose ground truth (the pixel-centre ray) is the ring: that ray and,
  // inside the ring's area, all of the pixel's samples end there; pixels on the area's border have some samples on
  // either side.
  const RayScene scene(SmallBoardScene(25).description);
  ASSERT_TRUE(scene.MountPathClear(0));
  raytrace::RenderOptions ro;
  ro.samples = 4;
  const raytrace::Frame f = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  const auto id = [&](int x, int y) {
    return f.truth.data[(static_cast<size_t>(y) * f.width + x) * raytrace::GroundTruth::kChannels + 7];
  };
  const float mount = static_cast<float>(raytrace::kMountId);
  uint64_t ring = 0, border = 0;
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x) {
      const bool on = id(x, y) == mount;
      ring += on;
      bool edge = false;
      for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
        const int xx = x + dx, yy = y + dy;
        if (xx >= 0 && yy >= 0 && xx < f.width && yy < f.height && (id(xx, yy) == mount) != on) edge = true;
      }
      border += edge;
    }
  ASSERT_GT(ring, 2000u);                                            // the image's corners, past the rim
  ASSERT_EQ(f.rays, static_cast<uint64_t>(5) * f.width * f.height);  // 4 samples and the ground-truth ray
  const double expected = static_cast<double>(f.rays) - 5.0 * static_cast<double>(ring);
  EXPECT_NEAR(static_cast<double>(f.embree_rays), expected, 4.0 * static_cast<double>(border))
      << "rays " << f.rays << ", ring pixels " << ring << ", border pixels " << border;
}

TEST(Texture, BatchTexturesAreTheScalarTexturesToTheBit) {
  // The vectorised noise (EvalInto) and Eval at the same points: identical. The noise spans its colour range,
  // is continuous (a 0.1 mm step changes it little) and stays defined far away (coordinates clamp).
  raytrace::Texture tex;
  tex.kind = raytrace::Texture::Kind::kNoise;
  tex.scale = 0.08, tex.octaves = 5, tex.seed = 11;
  tex.colour_a = {0.2f, 0.1f, 0.0f}, tex.colour_b = {0.8f, 0.9f, 1.0f};
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> U(-20, 20);
  const int n = 1001;
  std::vector<double> s(n), t(n);
  for (int i = 0; i < n; ++i) s[i] = U(rng), t[i] = U(rng);
  s[0] = 1e7, t[0] = -3e9;  // far: clamped
  std::vector<float> batch(3 * n);
  tex.EvalInto(n, s.data(), t.data(), batch.data());
  double lo = 1, hi = 0, step = 0;
  for (int i = 0; i < n; ++i) {
    const raytrace::Rgb one = tex.Eval(s[i], t[i]);
    for (int c = 0; c < 3; ++c) ASSERT_EQ(batch[3 * i + c], one[c]) << "point " << i;
    const double v = (batch[3 * i + 1] - tex.colour_a[1]) / (tex.colour_b[1] - tex.colour_a[1]);
    ASSERT_TRUE(v >= 0 && v <= 1) << v;
    lo = std::min(lo, v), hi = std::max(hi, v);
    step = std::max(step, std::abs(static_cast<double>(tex.Eval(s[i] + 1e-4, t[i])[1] - one[1])));
  }
  EXPECT_LT(lo, 0.3);
  EXPECT_GT(hi, 0.7);
  EXPECT_LT(step, 0.02) << "0.1 mm is 1/50 of the finest octave's cell";

  // The vectorised checkerboard likewise, on a 9 x 7 board of 30 mm squares: points inside, on the margin, on
  // square edges and far away (1e30 m, NaN-free clamping).
  raytrace::Texture board;
  board.kind = raytrace::Texture::Kind::kChecker;
  board.square = 0.03, board.squares_x = 9, board.squares_y = 7;
  board.colour_a = {0.1f, 0.1f, 0.1f}, board.colour_b = {0.9f, 0.8f, 0.7f}, board.margin = {1.0f, 0.5f, 0.25f};
  std::uniform_real_distribution<double> B(-0.2, 0.2);
  for (int i = 0; i < n; ++i) s[i] = B(rng), t[i] = B(rng);
  s[1] = 0.03, t[1] = 0.0;  // on an edge between squares
  s[2] = 1e30, t[2] = 0.01;
  s[3] = -0.135, t[3] = -0.105;  // the board's corner: inside
  board.EvalInto(n, s.data(), t.data(), batch.data());
  int margin = 0, dark = 0, light = 0;
  for (int i = 0; i < n; ++i) {
    const raytrace::Rgb one = board.Eval(s[i], t[i]);
    for (int c = 0; c < 3; ++c) ASSERT_EQ(batch[3 * i + c], one[c]) << "point " << i;
    margin += one == board.margin, dark += one == board.colour_a, light += one == board.colour_b;
  }
  EXPECT_GT(margin, 100);
  EXPECT_GT(dark, 100);
  EXPECT_GT(light, 100);
}

TEST(Render, BatchColoursAgreeWithTheScalarTrace) {
  // RayScene::Colours (the renderer's batched path) against Trace16 (the scalar shading) on the reflected rays
  // of a grid of pixels: the same colour except where a ray grazes a texture edge (float rounding of the hit).
  const SceneConfig cfg = BoardScene(true);
  const RayScene scene(cfg.description);
  const auto& unit = scene.description().units[0];
  raytrace::RayBatch b;
  raytrace::RayBatchF bf;  // the same rays in single precision (the renderer's colour samples)
  std::vector<float> rgb(3 * raytrace::RayBatch::kMax), rgb_f(rgb.size());
  int compared = 0, differ = 0, differ_f = 0;
  for (int y = 50; y < unit.rig.camera.height; y += 37) {
    b.n = 0;
    for (int x = 20; x < unit.rig.camera.width && b.n < raytrace::RayBatch::kMax; x += 11) {
      Vec3d M, d;
      if (!unit.rig.RayFromImg(Vec2d(x, y), &M, &d)) continue;
      const Vec3d o = unit.world_from_mirror * M, dw = unit.world_from_mirror.Rotate(d);
      const int i = b.n++;
      b.ox[i] = o.x(), b.oy[i] = o.y(), b.oz[i] = o.z(), b.dx[i] = dw.x(), b.dy[i] = dw.y(), b.dz[i] = dw.z();
      b.tnear[i] = 1e-5f, b.from_mirror[i] = 0, b.from_camera[i] = -1, b.mount_t[i] = -1, b.valid[i] = 1;
    }
    if (b.n == 0) continue;
    bf.n = b.n;
    for (int i = 0; i < b.n; ++i) {
      bf.ox[i] = static_cast<float>(b.ox[i]), bf.oy[i] = static_cast<float>(b.oy[i]);
      bf.oz[i] = static_cast<float>(b.oz[i]), bf.dx[i] = static_cast<float>(b.dx[i]);
      bf.dy[i] = static_cast<float>(b.dy[i]), bf.dz[i] = static_cast<float>(b.dz[i]);
      bf.tnear[i] = b.tnear[i], bf.from_mirror[i] = 0, bf.from_camera[i] = -1, bf.mount_t[i] = -1, bf.valid[i] = 1;
    }
    scene.Colours(b, rgb.data());
    scene.Colours(bf, rgb_f.data());
    for (int i = 0; i < b.n; ++i) {
      const raytrace::Hit h = scene.Trace(Vec3d(b.ox[i], b.oy[i], b.oz[i]), Vec3d(b.dx[i], b.dy[i], b.dz[i]), 1e-5, 0);
      ++compared;
      double worst = 0, worst_f = 0;
      for (int c = 0; c < 3; ++c) {
        worst = std::max(worst, std::abs(static_cast<double>(rgb[3 * i + c] - h.colour[c])));
        worst_f = std::max(worst_f, std::abs(static_cast<double>(rgb_f[3 * i + c] - h.colour[c])));
      }
      differ += worst > 1e-6;
      // Single precision moves texture coordinates by about 1e-7 m: the floor's noise (finest cell 5 mm) by
      // at most a few 1e-5 of its range; a checker edge only for rays within that of it.
      differ_f += worst_f > 1e-3;
    }
  }
  EXPECT_GT(compared, 5000);
  EXPECT_LE(differ, compared / 1000) << differ << " of " << compared;
  EXPECT_LE(differ_f, compared / 1000) << differ_f << " of " << compared << " (single precision)";
}

TEST(Render, GroundTruthOfMirrorPixelsIsTheScalarTrace) {
  // The ground-truth pass (RayScene::Geometry, runs of lanes evaluated together) against the scalar trace of
  // each mirror pixel's reflected ray, on a misaligned rig: the same object, point, normal and range.
  SceneConfig cfg = BoardScene(true);
  cfg.description.units[0].rig.camera = PinholeCamera<double>::FromPhysical(0.016, 4.54e-6 * 10, 275, 220);
  const RayScene scene(cfg.description);
  const auto& unit = scene.description().units[0];
  raytrace::RenderOptions ro;
  ro.samples = 1;
  const raytrace::Frame f = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  int compared = 0, differ = 0;
  std::map<int, int> ids;
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x) {
      Vec3d M, d;
      if (!unit.rig.RayFromImg(Vec2d(x, y), &M, &d)) continue;
      const Vec3d o = unit.world_from_mirror * M, dw = unit.world_from_mirror.Rotate(d);
      const raytrace::Hit h = scene.Trace(o, dw, 1e-5, 0);
      const float* g = &f.truth.data[(static_cast<size_t>(y) * f.width + x) * raytrace::GroundTruth::kChannels];
      ++compared, ++ids[static_cast<int>(g[7])];
      if (!h.hit) {
        differ += !(std::isinf(g[0]) && g[7] == 0 && g[1] == 0 && g[4] == 0);
        continue;
      }
      const Vec3d P(g[1], g[2], g[3]), N(g[4], g[5], g[6]);
      const bool same = g[7] == h.object_id && (P - h.point).norm() < 1e-5 * (1 + h.point.norm()) &&
                        (N - h.normal).norm() < 1e-6 &&
                        std::abs(g[0] - (h.point - unit.world_from_mirror.translation).norm()) < 1e-5;
      differ += !same;
    }
  EXPECT_GT(compared, 25000);
  EXPECT_LE(differ, compared / 1000) << differ << " of " << compared;
  EXPECT_GE(ids.size(), size_t(3)) << "sky, camera body, floor and boards are all seen";
}

TEST(RayScene, RawPacketsHitWhatTheDoublePathHits) {
  // The benchmark's raw reference (IntersectRaw: single-precision packets, rtcIntersect16 or two rtcIntersect8)
  // finds the same geometry as IntersectOnly16 (filled lane by lane from doubles) and the renderer's scalar
  // trace, for the reflected rays of a grid of pixels: a raw path that skipped geometry would look faster.
  const SceneConfig cfg = BoardScene(false);
  const RayScene scene(cfg.description);
  const auto& unit = scene.description().units[0];
  std::vector<Vec3d> o, d;
  for (int y = 40; y < unit.rig.camera.height; y += 29)
    for (int x = 30; x < unit.rig.camera.width; x += 23) {
      Vec3d M, dir;
      if (!unit.rig.RayFromImg(Vec2d(x, y), &M, &dir)) continue;
      o.push_back(unit.world_from_mirror * M), d.push_back(unit.world_from_mirror.Rotate(dir));
    }
  ASSERT_GT(o.size(), size_t(3000));
  int compared = 0, differ = 0, scalar_differ = 0;
  std::map<unsigned, int> seen;  // geometry id -> rays
  const int from[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (size_t p = 0; p + 16 <= o.size(); p += 16) {
    RayScene::RawPacket16 packet;
    for (int i = 0; i < 16; ++i) {
      packet.ox[i] = float(o[p + i].x()), packet.oy[i] = float(o[p + i].y()), packet.oz[i] = float(o[p + i].z());
      packet.dx[i] = float(d[p + i].x()), packet.dy[i] = float(d[p + i].y()), packet.dz[i] = float(d[p + i].z());
    }
    unsigned raw16[16], raw8[16], from_double[16];
    scene.IntersectRaw(packet, 0, 16, raw16);
    scene.IntersectRaw(packet, 0, 8, raw8);
    scene.IntersectOnly16(16, &o[p], &d[p], from_double, from);
    for (int i = 0; i < 16; ++i) {
      ++compared, ++seen[raw16[i]];
      differ += raw16[i] != from_double[i] || raw8[i] != from_double[i];
      const raytrace::Hit h = scene.Trace(o[p + i], d[p + i], 0, 0);
      scalar_differ += h.hit != (raw16[i] != RTC_INVALID_GEOMETRY_ID);
    }
  }
  EXPECT_EQ(differ, 0) << " of " << compared;
  EXPECT_LE(scalar_differ, compared / 1000) << " of " << compared;
  // The rays meet the floor, the boards, the room and the camera body, and some go to the sky.
  EXPECT_GE(seen.size(), size_t(3));
  EXPECT_GT(seen[RTC_INVALID_GEOMETRY_ID], 0);
  EXPECT_LT(seen[RTC_INVALID_GEOMETRY_ID], compared / 2);
  EXPECT_THROW(
      {
        unsigned ids[16];
        scene.IntersectRaw(RayScene::RawPacket16{}, 0, 4, ids);
      },
      Error);
}

// A frame larger than the memory left is refused before any of it is taken, with its size and both amounts in
// the message (Linux would let the allocation succeed and kill the process when it touches the pages), and the
// memory a frame's buffers already hold counts.
TEST(Render, FramesLargerThanTheMemoryLeftAreRefusedWithTheirSize) {
  const std::size_t full = raytrace::FrameMemoryBytes(2750, 2200, true);
  EXPECT_EQ(full, std::size_t(2750) * 2200 * 4 * 18);  // RGB, 12 ground-truth channels, the sensor image
  EXPECT_EQ(raytrace::FrameMemoryBytes(2750, 2200, false), std::size_t(2750) * 2200 * 4 * 6);
  try {
    raytrace::CheckFrameMemory("render (unit u)", 2750, 2200, true, 0, full - 1);
    ADD_FAILURE() << "a frame one byte too large was accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    for (const char* needle : {"render (unit u)", "2750 x 2200", "with ground truth", "0.44 GB", "are available"})
      EXPECT_NE(what.find(needle), std::string::npos) << needle << " in: " << what;
  }
  EXPECT_NO_THROW(raytrace::CheckFrameMemory("render", 2750, 2200, true, 0, full));
  EXPECT_NO_THROW(raytrace::CheckFrameMemory("render", 2750, 2200, true, full / 2, full / 2));  // reused buffers
  EXPECT_THROW(raytrace::CheckFrameMemory("render", 2750, 2200, true, full / 2, full / 2 - 1), Error);
  EXPECT_NO_THROW(raytrace::CheckFrameMemory("render", 20000, 20000, true, 0, std::nullopt));  // unknown: no check
  // This machine's figure exists (Linux) and is no more than its physical memory plus what the process keeps.
  const auto available = AvailableMemoryBytes();
  ASSERT_TRUE(available.has_value());
  EXPECT_GT(*available, std::size_t(0));
  EXPECT_LE(*available,
            static_cast<std::size_t>(sysconf(_SC_PHYS_PAGES)) * static_cast<std::size_t>(sysconf(_SC_PAGE_SIZE)) +
                KeptLargePageBytes());
  // A render of a camera past it is refused by RenderInto itself, before the frame changes.
  SceneConfig cfg = BoardScene(false);
  cfg.description.units[0].rig.camera = PinholeCamera<double>::FromPhysical(0.016, 4.54e-6, 20000, 20000);
  if (raytrace::FrameMemoryBytes(20000, 20000, true) > *available) {
    raytrace::Frame f;
    raytrace::RenderOptions ro;
    ro.samples = 1;
    EXPECT_THROW(raytrace::RenderInto(RayScene(cfg.description), raytrace::ViewCamera::Unit(0), ro, &f), Error);
    EXPECT_TRUE(f.rgb.empty());
  }
}

// Frames rendered into memory that held another frame (RenderInto's reused buffers, or a freed buffer that
// AllocateLargePages hands out again) are the frames rendered into fresh memory, to the bit: every pixel and
// channel is written, and a region render zeroes the rest. At 344 x 275 the ground truth (4.5 MB) is a large
// buffer, so it goes through the kept-buffer path.
TEST(Render, FramesInReusedMemoryAreTheFramesInFreshMemory) {
  const auto small = [](bool misaligned) {
    SceneConfig cfg = BoardScene(misaligned);
    cfg.description.units[0].rig.camera = PinholeCamera<double>::FromPhysical(0.016, 4.54e-6 * 8, 344, 275);
    return cfg;
  };
  const RayScene before(small(true).description), after(small(false).description);
  raytrace::RenderOptions first, second;
  first.samples = 4, first.seed = 11, first.ground_truth = true;
  second.samples = 1, second.seed = 5, second.ground_truth = true;
  raytrace::RenderOptions region = second;
  region.region = {60, 40, 250, 200};
  const auto same = [](const raytrace::Frame& a, const raytrace::Frame& b) {
    return a.width == b.width && a.height == b.height && a.rgb.size() == b.rgb.size() &&
           a.truth.data.size() == b.truth.data.size() &&
           std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)) == 0 &&
           std::memcmp(a.truth.data.data(), b.truth.data.data(), a.truth.data.size() * sizeof(float)) == 0;
  };
  const size_t previous_limit = KeepFreedLargePages(0);  // fresh memory for the references
  const auto fresh = raytrace::Render(after, raytrace::ViewCamera::Unit(0), second);
  const auto fresh_region = raytrace::Render(after, raytrace::ViewCamera::Unit(0), region);
  ASSERT_GE(fresh.truth.data.size() * sizeof(float), kLargeBytes);
  ASSERT_FALSE(same(fresh, fresh_region));

  for (const auto* opts : {&second, &region}) {
    const auto& reference = opts == &second ? fresh : fresh_region;
    // Reused buffers.
    raytrace::Frame f = raytrace::Render(before, raytrace::ViewCamera::Unit(0), first);
    raytrace::RenderInto(after, raytrace::ViewCamera::Unit(0), *opts, &f);
    EXPECT_TRUE(same(f, reference)) << "RenderInto, region " << (opts == &region);
    // A kept buffer handed out again.
    KeepFreedLargePages(std::size_t(64) << 20);
    { const auto discarded = raytrace::Render(before, raytrace::ViewCamera::Unit(0), first); }
    EXPECT_GE(KeptLargePageBytes(), kLargeBytes);
    const auto g = raytrace::Render(after, raytrace::ViewCamera::Unit(0), *opts);
    EXPECT_EQ(KeptLargePageBytes(), 0u) << "the ground truth did not take the kept buffer";
    EXPECT_TRUE(same(g, reference)) << "kept buffer, region " << (opts == &region);
    KeepFreedLargePages(0);
  }
  KeepFreedLargePages(previous_limit);
}

TEST(GoldenRender, SmallReferenceFrameIsUnchanged) {
  SceneConfig cfg = BoardScene(false);
  auto& cam = cfg.description.units[0].rig.camera;
  cam = PinholeCamera<double>::FromPhysical(0.016, 4.54e-6 * 8, 344, 275);
  const RayScene scene(cfg.description);
  raytrace::RenderOptions ro;
  ro.samples = 4;
  ro.seed = 3;
  ro.ground_truth = false;
  const raytrace::Frame f = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  int ch = 0;
  const auto img = raytrace::ApplySensor(f, ro.sensor, 1, &ch);
  const std::filesystem::path golden = std::string(HOVS_SOURCE_DIR) + "/tests/data/golden_reference_board.png";
  if (std::getenv("HOVS_UPDATE_GOLDEN")) {
    io::WriteImage(golden, f.width, f.height, ch, img, 8);
    GTEST_SKIP() << "golden image rewritten: " << golden;
  }
  int w = 0, h = 0, gc = 0;
  const auto ref = io::ReadImage(golden, &w, &h, &gc);
  ASSERT_EQ(w, f.width);
  ASSERT_EQ(h, f.height);
  ASSERT_EQ(gc, ch);
  double sum = 0;
  int off = 0;
  for (size_t i = 0; i < ref.size(); ++i) {
    const double d = std::abs(std::round(img[i] * 255) - std::round(ref[i] * 255));
    sum += d;
    off += d > 2;
  }
  EXPECT_LT(sum / ref.size(), 0.25) << "mean absolute difference, 8-bit levels";
  EXPECT_LT(off, static_cast<int>(ref.size() / 1000)) << "values off by more than 2 levels";
}

}  // namespace
}  // namespace hovs
