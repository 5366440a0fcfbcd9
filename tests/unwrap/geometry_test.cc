// Unwrap geometry against the renderer: a catadioptric render unwrapped into a virtual perspective view is
// compared with a pinhole render of the same view (the same K and pose, placed at the viewpoint): board
// corners found in the unwrapped view against their exact projection (at most 0.2 px), and PSNR over the view
// (at least 35 dB); for the exact model and for a polynomial model calibrated from board corners. A vertical
// world edge stays vertical in the cylindrical panorama (within 0.2 px).
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <optional>

#include "calib/checkerboard_edges.h"
#include "calib/polynomial_calibration.h"
#include "raytrace/render.h"
#include "scenes/dataset.h"
#include "scenes/ground_truth.h"
#include "scenes/scene_config.h"
#include "unwrap/remap.h"
#include "io/image_io.h"

namespace hovs::unwrap {
namespace {

using scenes::SceneConfig;
constexpr double kDeg = M_PI / 180;

SceneConfig BoardScene() {
  return scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_board.yaml");
}

// The frame as 8-bit RGB (the same quantisation for both renders).
std::vector<uint8_t> ToRgb8(const raytrace::Frame& f) {
  std::vector<uint8_t> out(f.rgb.size());
  for (size_t k = 0; k < f.rgb.size(); ++k) out[k] = uint8_t(std::lround(std::clamp(f.rgb[k], 0.f, 1.f) * 255));
  return out;
}

// Bounding box (level-0 source pixels) of what a table samples, padded.
raytrace::RenderOptions::Region SourceRegion(const RemapTable& t, int pad) {
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (size_t v = 0; v < t.views.size(); ++v) {
    std::vector<float> mx, my;
    t.DecodeView(static_cast<int>(v), &mx, &my);
    for (size_t k = 0; k < mx.size(); ++k) {
      if (mx[k] < 0) continue;
      x0 = std::min<double>(x0, mx[k]), x1 = std::max<double>(x1, mx[k]);
      y0 = std::min<double>(y0, my[k]), y1 = std::max<double>(y1, my[k]);
    }
  }
  return {std::max(0, int(x0) - pad), std::max(0, int(y0) - pad), std::min(t.source_width, int(x1) + pad),
          std::min(t.source_height, int(y1) + pad)};
}

struct Comparison {
  double corner_rms = 0, corner_max = 0, psnr = 0, reference_corner_rms = 0;
  double edges_rms = 0, edges_max = 0, reference_edges_rms = 0;  // corners from the board's edges
};

// Unwraps the catadioptric render with `model` into `spec` and compares with the pinhole render.
Comparison CompareWithPinhole(const SceneConfig& cfg, const AnyModel& model, const ViewSpec& spec, int samples,
                              Interpolation interp) {
  const raytrace::RayScene scene(cfg.description);
  const auto& unit = scene.description().units[0];
  Layout layout;
  layout.name = "test";
  layout.views = {spec};
  const RemapTable table = BuildRemapTable(model, layout, {});
  const VirtualView<double> view = spec.View();
  const Rigid3d world_from_view = unit.world_from_mirror * Rigid3d(view.mirror_from_view, Vec3d::Zero());

  raytrace::RenderOptions ro;
  ro.samples = samples;
  ro.ground_truth = false;
  ro.region = SourceRegion(table, 4);
  const raytrace::Frame cata = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  raytrace::RenderOptions rp = ro;
  rp.region = {};
  // The pinhole sits at the viewpoint F1, inside the mirror: it sees the world without the unit's own hardware.
  raytrace::SceneDescription bare = cfg.description;
  bare.units.clear();
  const raytrace::RayScene bare_scene(bare);
  const raytrace::Frame pin =
      raytrace::Render(bare_scene, raytrace::ViewCamera::Pinhole(view.camera, world_from_view), rp);

  const std::vector<uint8_t> cata8 = ToRgb8(cata), pin8 = ToRgb8(pin);
  Remapper remapper(table);
  std::vector<Image8> out;
  remapper.Run({cata8.data(), cata.width, cata.height, size_t(cata.width) * 3, PixelFormat::kRgb8}, interp, &out);
  const Image8& u = out[0];
  if (std::getenv("HOVS_DUMP_UNWRAP")) {
    io::WriteImage(
        std::string(std::getenv("HOVS_DUMP_UNWRAP")) + "_unwrap.png", u.width, u.height, 3,
        [&] {
          std::vector<float> f(u.data.size());
          for (size_t k = 0; k < f.size(); ++k) f[k] = u.data[k] / 255.f;
          return f;
        }(),
        8);
    io::WriteImage(std::string(std::getenv("HOVS_DUMP_UNWRAP")) + "_pinhole.png", pin.width, pin.height, 3,
                   std::vector<float>(pin.rgb.begin(), pin.rgb.end()), 8);
  }

  Comparison c;
  // PSNR over the valid pixels.
  std::vector<float> mx, my;
  table.DecodeView(0, &mx, &my);
  double se = 0;
  int64_t n = 0;
  for (size_t k = 0; k < mx.size(); ++k) {
    if (mx[k] < 0) continue;
    for (int ch = 0; ch < 3; ++ch) se += std::pow(double(u.data[3 * k + ch]) - pin8[3 * k + ch], 2);
    n += 3;
  }
  EXPECT_GT(n, int64_t(mx.size()) * 3 * 9 / 10) << "most of the view must be valid";
  c.psnr = 10 * std::log10(255.0 * 255.0 / (se / n));

  // Corners: exact projection through the view camera vs cornerSubPix in the unwrapped (and pinhole) image.
  const auto grey = [](const uint8_t* rgb, int w, int h) {
    cv::Mat g(h, w, CV_32F);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) g.at<float>(y, x) = rgb[3 * (y * w + x) + 1];
    return g;
  };
  const auto& board = cfg.boards[0];
  const Rigid3d view_from_world = world_from_view.Inverse();
  std::vector<Vec2d> truth;
  std::vector<int> cell;  // grid index (row-major over the board's inner corners) of each truth corner
  const int cols = board.spec.squares_x - 1;
  for (const auto& [id, p] : board.spec.Corners()) {
    Vec2d uv(-1, -1);
    EXPECT_TRUE(view.camera.ImgFromCam(view_from_world * (board.world_from_board * Vec3d(p.x(), p.y(), 0)), &uv));
    if (uv.x() > 8 && uv.y() > 8 && uv.x() < view.width - 9 && uv.y() < view.height - 9) {
      truth.push_back(uv);
      const int gi = static_cast<int>(std::lround(p.x() / board.spec.square + 0.5 * (board.spec.squares_x - 2)));
      const int gj = static_cast<int>(std::lround(p.y() / board.spec.square + 0.5 * (board.spec.squares_y - 2)));
      cell.push_back(gj * cols + gi);
    }
  }
  EXPECT_EQ(truth.size(), 35u) << "the whole board must be inside the view";
  // cornerSubPix, then (edges) the corners from the board's edges in the 8-bit image.
  const auto measure = [&](const cv::Mat& g, bool edges, double* rms, double* worst) {
    std::vector<cv::Point2f> pts;
    for (const auto& t : truth) pts.emplace_back(float(t.x() + 0.6), float(t.y() - 0.4));
    cv::cornerSubPix(g, pts, cv::Size(5, 5), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 200, 1e-5));
    std::vector<Vec2d> found;
    for (const auto& p : pts) found.emplace_back(p.x, p.y);
    if (edges) {
      std::vector<std::optional<Vec2d>> grid(static_cast<size_t>(cols) * (board.spec.squares_y - 1));
      for (size_t i = 0; i < found.size(); ++i) grid[cell[i]] = found[i];
      cv::Mat g8;
      g.convertTo(g8, CV_8U);
      const auto refined = calib::RefineCheckerboardCornersByEdges(g8, cols, board.spec.squares_y - 1, &grid);
      int from_edges = 0;
      for (size_t i = 0; i < found.size(); ++i) found[i] = *grid[cell[i]], from_edges += refined[cell[i]];
      EXPECT_EQ(from_edges, static_cast<int>(found.size())) << "every corner refined from the edges";
    }
    double s2 = 0;
    *worst = 0;
    for (size_t i = 0; i < found.size(); ++i) {
      const double e = (found[i] - truth[i]).norm();
      s2 += e * e;
      *worst = std::max(*worst, e);
    }
    *rms = std::sqrt(s2 / found.size());
  };
  double ref_max = 0;
  const cv::Mat gu = grey(u.data.data(), u.width, u.height), gp = grey(pin8.data(), pin.width, pin.height);
  measure(gu, false, &c.corner_rms, &c.corner_max);
  measure(gp, false, &c.reference_corner_rms, &ref_max);
  measure(gu, true, &c.edges_rms, &c.edges_max);
  measure(gp, true, &c.reference_edges_rms, &ref_max);
  return c;
}

ViewSpec BoardView(const SceneConfig& cfg) {
  // A 480 x 360 view centred on the board, as seen from the unit's viewpoint.
  const Vec3d d = cfg.description.units[0].world_from_mirror.Inverse() * cfg.boards[0].world_from_board.translation;
  ViewSpec v;
  v.name = "board";
  v.width = 480, v.height = 360, v.hfov_deg = 40;
  v.yaw_deg = std::atan2(d.y(), d.x()) / kDeg + 2;  // off-centre on purpose
  v.pitch_deg = std::atan2(d.z(), d.head<2>().norm()) / kDeg - 1.5;
  v.roll_deg = 4;
  return v;
}

// Bilinear (the real-time default) and bicubic. The view samples the mirror image at about one source pixel per
// view pixel, where bilinear interpolation visibly smooths the floor texture: the 35 dB bar is asserted for
// bicubic, bilinear must stay within 2 dB of it; corners within 0.2 px for both (cornerSubPix), and within
// 0.06 px measured from the board's edges.
void CheckAgainstPinhole(const SceneConfig& cfg, const AnyModel& model, const char* what) {
  const Comparison bl = CompareWithPinhole(cfg, model, BoardView(cfg), 16, Interpolation::kBilinear);
  const Comparison bc = CompareWithPinhole(cfg, model, BoardView(cfg), 16, Interpolation::kBicubic);
  for (const auto& [name, c] : {std::pair<const char*, const Comparison&>{"bilinear", bl}, {"bicubic", bc}}) {
    std::printf("[ figure ] %s, %s: corners RMS %.4f px (max %.4f; in the pinhole render itself %.4f), PSNR %.2f dB\n",
                what, name, c.corner_rms, c.corner_max, c.reference_corner_rms, c.psnr);
    std::printf(
        "[ figure ] %s, %s: corners from the edges RMS %.4f px (max %.4f; in the pinhole render itself "
        "%.4f)\n",
        what, name, c.edges_rms, c.edges_max, c.reference_edges_rms);
    EXPECT_LE(c.corner_max, 0.2) << what << " " << name;
    // Measured from the edges the corners show the geometry itself (the same figure in the pinhole render):
    // a bar several times tighter than the issue's.
    EXPECT_LE(c.edges_max, 0.06) << what << " " << name;
  }
  EXPECT_GE(bc.psnr, 35.0) << what;
  EXPECT_GE(bl.psnr, bc.psnr - 2.0) << what;
}

TEST(UnwrapGeometry, ExactModelMatchesAPinholeRenderOfTheSameView) {
  const SceneConfig cfg = BoardScene();
  CheckAgainstPinhole(cfg, AnyModel::Exact(cfg.description.units[0].rig), "exact model");
}

TEST(UnwrapGeometry, CalibratedPolynomialModelMatchesAPinholeRenderOfTheSameView) {
  const SceneConfig cfg = BoardScene();
  const auto& unit = cfg.description.units[0];
  // Calibrate the polynomial model from the article's 9 board poses (exact corners, the calibration set's poses).
  auto opts = scenes::DatasetOptions::ForKind("mono_calibration");
  const auto poses = scenes::DrawBoardPoses(cfg, opts);
  std::vector<calib::BoardObservation> obs;
  const Rigid3d mirror_from_world = unit.world_from_mirror.Inverse();
  for (size_t i = 0; i < poses.size(); ++i) {
    calib::BoardObservation o;
    o.image = "pose" + std::to_string(i);
    for (const auto& [id, p] : opts.board.Corners()) {
      Vec2d uv;
      if (unit.rig.ImgFromMirror(mirror_from_world * (poses[i] * Vec3d(p.x(), p.y(), 0)), &uv) != ProjectionStatus::kOk)
        continue;
      o.board_points.emplace_back(p.x(), p.y(), 0);
      o.pixels.push_back(uv);
    }
    obs.push_back(o);
  }
  calib::PolynomialCalibrationOptions po;
  po.degree = 4;
  const auto cal = calib::CalibratePolynomial(obs, unit.rig.camera.width, unit.rig.camera.height, po);
  ASSERT_LT(cal.rms, 0.05);
  std::printf("[ figure ] polynomial model calibrated from 9 x 35 exact corners: RMS %.5f px\n", cal.rms);
  CheckAgainstPinhole(cfg, AnyModel::Polynomial(cal.model), "calibrated polynomial");
}

TEST(UnwrapGeometry, VerticalEdgeStaysVerticalInTheCylindricalPanorama) {
  // A tall plane, dark left half and light right half, facing the unit: its boundary is a vertical line whose
  // azimuth from the viewpoint is known. The panorama column of the edge, found per row at sub-pixel precision,
  // must equal the column of that azimuth.
  SceneConfig cfg = BoardScene();
  auto& desc = cfg.description;
  desc.rects.clear();
  cfg.boards.clear();
  const Vec3d F1 = desc.units[0].world_from_mirror.translation;
  const double az = 25 * kDeg, dist = 2.0;
  const Rigid3d centre = scenes::LookAt(F1 + Vec3d(dist * std::cos(az), dist * std::sin(az), 1.2 - F1.z()),
                                        F1 + Vec3d(0, 0, 1.2 - F1.z()));
  for (int side : {-1, 1}) {
    raytrace::Rect r;
    r.object_id = raytrace::kFirstObjectId + (side > 0);
    r.width = 0.8, r.height = 3.0;
    r.world_from_rect = centre * Rigid3d::Translation(Vec3d(0.4 * side, 0, 0));
    r.front.kind = raytrace::Texture::Kind::kSolid;
    r.front.colour_a = side < 0 ? raytrace::Rgb{0.1f, 0.1f, 0.1f} : raytrace::Rgb{0.9f, 0.9f, 0.9f};
    desc.rects.push_back(r);
  }
  const raytrace::RayScene scene(desc);

  Layout layout;
  layout.name = "pano";
  ViewSpec p;
  p.name = "pano", p.type = ViewProjection::kCylindrical, p.width = 3600, p.height = 600;
  p.elevation_min_deg = -60, p.elevation_max_deg = -5;
  layout.views = {p};
  const AnyModel model = AnyModel::Exact(desc.units[0].rig);
  const RemapTable table = BuildRemapTable(model, layout, {});
  const VirtualView<double> view = p.View();
  Vec2d edge_uv;
  ASSERT_TRUE(view.ImgFromMirror(Vec3d(std::cos(az), std::sin(az), -0.2), &edge_uv));
  const double expect_u = edge_uv.x();

  // Render only the part of the image around the edge's azimuth.
  raytrace::RenderOptions ro;
  ro.samples = 16;
  ro.ground_truth = false;
  {
    std::vector<float> mx, my;
    table.DecodeView(0, &mx, &my);
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (int v = 0; v < p.height; ++v)
      for (int u = int(expect_u) - 12; u <= int(expect_u) + 12; ++u) {
        const size_t k = size_t(v) * p.width + u;
        if (mx[k] < 0) continue;
        x0 = std::min<double>(x0, mx[k]), x1 = std::max<double>(x1, mx[k]);
        y0 = std::min<double>(y0, my[k]), y1 = std::max<double>(y1, my[k]);
      }
    ro.region = {int(x0) - 4, int(y0) - 4, int(x1) + 5, int(y1) + 5};
  }
  const raytrace::Frame f = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  const std::vector<uint8_t> rgb = ToRgb8(f);
  Remapper remapper(table);
  std::vector<Image8> out;
  remapper.Run({rgb.data(), f.width, f.height, size_t(f.width) * 3, PixelFormat::kRgb8}, Interpolation::kBilinear,
               &out);

  // Per row: the 50 % crossing between the dark and the light level, interpolated linearly. Rows whose
  // neighbourhood of the edge is not fully on the plane are skipped.
  double worst = 0;
  int rows = 0;
  for (int v = 0; v < p.height; ++v) {
    const uint8_t* row = out[0].data.data() + size_t(v) * p.width * 3;
    const int c0 = int(expect_u) - 10, c1 = int(expect_u) + 10;
    const double dark = row[3 * c0 + 1], light = row[3 * c1 + 1];
    if (light - dark < 150) continue;  // not on the plane (sky, ground or the plane's border)
    const double mid = 0.5 * (dark + light);
    for (int u = c0; u < c1; ++u) {
      const double a = row[3 * u + 1], b = row[3 * (u + 1) + 1];
      // Dark on the left when the panorama reads left to right with decreasing azimuth.
      if ((a - mid) * (b - mid) <= 0 && a != b) {
        const double cross = u + (mid - a) / (b - a);
        worst = std::max(worst, std::abs(cross - expect_u));
        ++rows;
        break;
      }
    }
  }
  std::printf("[ figure ] vertical edge in the cylindrical panorama: %d rows, worst column deviation %.4f px\n", rows,
              worst);
  EXPECT_GT(rows, 100);
  EXPECT_LE(worst, 0.2);
  RecordProperty("vertical_edge_worst_px", std::to_string(worst));
}

}  // namespace
}  // namespace hovs::unwrap
