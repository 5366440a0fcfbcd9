#include "depth/stereo.h"

#include <OpenImageIO/imageio.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <iomanip>
#include <sstream>

#include "core/error.h"
#include "core/io.h"

namespace hovs::depth {
namespace {
constexpr double kDeg = M_PI / 180;

// Closest points of the rays o1 + s d1 and o2 + t d2: (s, t), false for (near-)parallel rays.
bool ClosestParameters(const Vec3d& o1, const Vec3d& d1, const Vec3d& o2, const Vec3d& d2, double* s, double* t) {
  const Vec3d w = o1 - o2;
  const double a = d1.dot(d1), b = d1.dot(d2), c = d2.dot(d2), d = d1.dot(w), e = d2.dot(w);
  const double den = a * c - b * b;
  if (!(den > 1e-14 * a * c)) return false;
  *s = (b * e - c * d) / den;
  *t = (a * e - b * d) / den;
  return true;
}

// Two unit vectors orthogonal to b (a tangent basis for angular perturbations).
void TangentBasis(const Vec3d& b, Vec3d* e1, Vec3d* e2) {
  const Vec3d helper = std::abs(b.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY();
  *e1 = b.cross(helper).normalized();
  *e2 = b.cross(*e1).normalized();
}

}  // namespace

double LawOfSinesRange(double baseline, double theta_left, double theta_right) {
  return baseline * std::sin(theta_right) / std::sin(theta_right - theta_left);
}

Triangulation Triangulate(const StereoRig& rig, const Vec3d& bearing_left, const Vec3d& bearing_right,
                          double sigma_angle_rad) {
  return Triangulate(rig, Vec3d::Zero(), bearing_left, Vec3d::Zero(), bearing_right, sigma_angle_rad);
}

Triangulation Triangulate(const StereoRig& rig, const Vec3d& origin_left, const Vec3d& bearing_left,
                          const Vec3d& origin_right, const Vec3d& bearing_right, double sigma_angle_rad) {
  Triangulation out;
  const Rigid3d left_from_right = rig.right_from_left.Inverse();
  const Vec3d oL = origin_left, oR = left_from_right * origin_right;
  const auto solve = [&](const Vec3d& bl, const Vec3d& br, Vec3d* X, double* gap) {
    const Vec3d dL = bl.normalized(), dR = (left_from_right.rotation * br).normalized();
    double s, t;
    if (!ClosestParameters(oL, dL, oR, dR, &s, &t) || !(s > 0) || !(t > 0)) return false;
    const Vec3d pL = oL + s * dL, pR = oR + t * dR;
    *X = 0.5 * (pL + pR);
    if (gap) *gap = (pL - pR).norm();
    return true;
  };
  if (!solve(bearing_left, bearing_right, &out.point_left, &out.gap)) return out;
  out.ok = true;
  out.range_left = out.point_left.norm();
  // First-order propagation: range derivative along two tangent directions of each bearing.
  const double h = 1e-7;
  double var = 0;
  Vec3d e[4];
  TangentBasis(bearing_left.normalized(), &e[0], &e[1]);
  TangentBasis(bearing_right.normalized(), &e[2], &e[3]);
  for (int k = 0; k < 4; ++k) {
    Vec3d bl = bearing_left.normalized(), br = bearing_right.normalized();
    (k < 2 ? bl : br) += h * e[k];
    Vec3d X;
    if (!solve(bl, br, &X, nullptr)) continue;
    const double dr = (X.norm() - out.range_left) / h;
    var += dr * dr;
  }
  out.sigma_range = std::sqrt(var) * sigma_angle_rad;
  return out;
}

void RectifyOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(width >= 16 && height >= 16 && width <= 16384 && height <= 16384, where,
               "rectified size must be 16..16384 pixels");
  HOVS_REQUIRE(theta_min_deg >= 0 && theta_max_deg <= 180 && theta_min_deg < theta_max_deg, where,
               "theta range must lie in [0, 180] degrees");
  HOVS_REQUIRE(phi_min_deg < phi_max_deg && phi_max_deg - phi_min_deg <= 360, where, "bad phi range");
}

double Rectification::ThetaAt(double u) const { return options.theta_max_deg * kDeg - (u + 0.5) * dtheta; }

Vec3d Rectification::LeftBearing(double u, double v) const {
  Vec3d b;
  left.views[0].view.MirrorFromImg(Vec2d(u, v), &b);
  return b;
}

Rectification Rectify(const StereoRig& rig, const RectifyOptions& o) {
  o.Check("rectification");
  Rectification r;
  r.options = o;
  const Vec3d t = rig.RightCentreInLeft();
  r.baseline = t.norm();
  HOVS_REQUIRE(r.baseline > 1e-6, "stereo rig", "the two viewpoints coincide (no baseline)");
  // Shared epipolar frame in the left mirror frame: x along the baseline, z as close to the mirror axis as
  // possible (up for upright units), y = z x x.
  const Vec3d ex = t / r.baseline;
  Vec3d ez = Vec3d::UnitZ() - ex.z() * ex;
  HOVS_REQUIRE(ez.norm() > 1e-3, "stereo rig", "the baseline is along the mirror axis: no rectification frame");
  ez.normalize();
  const Vec3d ey = ez.cross(ex);
  Mat3<double> R;
  R.col(0) = ex, R.col(1) = ey, R.col(2) = ez;
  r.left_from_rect = Eigen::Quaterniond(R);
  r.right_from_rect = rig.right_from_left.rotation * r.left_from_rect;
  r.dtheta = (o.theta_max_deg - o.theta_min_deg) * kDeg / o.width;

  unwrap::ViewSpec spec;
  spec.type = ViewProjection::kEpipolar;
  spec.width = o.width, spec.height = o.height;
  spec.azimuth_centre_deg = 0.5 * (o.theta_min_deg + o.theta_max_deg);
  spec.azimuth_span_deg = o.theta_max_deg - o.theta_min_deg;
  spec.elevation_min_deg = o.phi_min_deg, spec.elevation_max_deg = o.phi_max_deg;
  unwrap::Layout layout;
  layout.name = "epipolar";
  spec.name = "left";
  spec.pole = r.left_from_rect;
  layout.views = {spec};
  r.left = unwrap::BuildRemapTable(rig.left, layout, {});
  spec.name = "right";
  spec.pole = r.right_from_rect;
  layout.views = {spec};
  r.right = unwrap::BuildRemapTable(rig.right, layout, {});
  return r;
}

void DenseOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(num_disparities >= 16 && num_disparities <= 4096 && num_disparities % 16 == 0, where,
               "num_disparities must be a multiple of 16 in 16..4096 (got ", num_disparities, ")");
  HOVS_REQUIRE(block_size >= 1 && block_size % 2 == 1 && block_size <= 21, where, "block_size must be odd, 1..21");
  HOVS_REQUIRE(std::isfinite(sigma_disparity_px) && sigma_disparity_px > 0 && sigma_disparity_px <= 100, where,
               "sigma_disparity_px must be in (0, 100] (got ", sigma_disparity_px, ")");
  HOVS_REQUIRE(std::isfinite(max_relative_sigma) && max_relative_sigma > 0 && max_relative_sigma <= 10, where,
               "max_relative_sigma must be in (0, 10] (got ", max_relative_sigma, ")");
  HOVS_REQUIRE(std::isfinite(min_theta_deg) && min_theta_deg >= 0 && min_theta_deg < 90, where,
               "min_theta_deg must be in [0, 90) (got ", min_theta_deg, ")");
  HOVS_REQUIRE(refine_radius >= 2 && refine_radius <= 16, where, "refine_radius must be in 2..16 (got ", refine_radius,
               ")");
}

namespace {

// SGBM 3-way disparity (CV_16S, 16 x columns) of a grey pair. SGBM gives no disparity to the first
// num_disparities columns (their match would lie left of the image): both images are padded on the left
// (replicated border) and the result cropped; near theta_max the true disparity is small, so real matches stay
// inside the real image.
cv::Mat MatchSgbm(const cv::Mat& gl, const cv::Mat& gr, int num_disparities, int bs, int speckle_window = 100) {
  auto sgbm = cv::StereoSGBM::create(0, num_disparities, bs, 8 * bs * bs, 32 * bs * bs, 1, 31, 10, speckle_window, 2,
                                     cv::StereoSGBM::MODE_SGBM_3WAY);
  cv::Mat pl, pr, disp_padded;
  const int pad = num_disparities;
  cv::copyMakeBorder(gl, pl, 0, 0, pad, 0, cv::BORDER_REPLICATE);
  cv::copyMakeBorder(gr, pr, 0, 0, pad, 0, cv::BORDER_REPLICATE);
  sgbm->compute(pl, pr, disp_padded);
  return disp_padded.colRange(pad, pad + gl.cols).clone();
}

// Disparity in columns (float; <= 0: none) by SGBM at half resolution and a block search at full resolution
// around it (DenseOptions::coarse_to_fine).
cv::Mat MatchCoarseToFine(const cv::Mat& gl, const cv::Mat& gr, const DenseOptions& o) {
  const int W = gl.cols, H = gl.rows, R = o.refine_radius, half_bs = o.block_size / 2;
  cv::Mat hl, hr;
  cv::pyrDown(gl, hl);
  cv::pyrDown(gr, hr);
  const int nd_half = std::max(16, ((o.num_disparities / 2 + 15) / 16) * 16);
  const cv::Mat coarse = MatchSgbm(hl, hr, nd_half, o.block_size, 25);  // speckle window: 100 full-res pixels
  // The coarse disparity at full resolution (bilinear between the half-resolution samples where all four have
  // one, else the nearest), rounded to whole columns (-1: none). Half-resolution pixel (x, y) covers full
  // resolution (2x + 0.5, 2y + 0.5).
  cv::Mat d0(H, W, CV_32S), d0f(H, W, CV_32F);
  tbb::parallel_for(0, H, [&](int v) {
    const double y = std::clamp((v - 0.5) / 2.0, 0.0, coarse.rows - 1.0);
    const int y0 = std::min(static_cast<int>(y), coarse.rows - 1), y1 = std::min(y0 + 1, coarse.rows - 1);
    const double fy = y - y0;
    int* out = d0.ptr<int>(v);
    for (int u = 0; u < W; ++u) {
      const double x = std::clamp((u - 0.5) / 2.0, 0.0, coarse.cols - 1.0);
      const int x0 = std::min(static_cast<int>(x), coarse.cols - 1), x1 = std::min(x0 + 1, coarse.cols - 1);
      const double fx = x - x0;
      const short a = coarse.at<short>(y0, x0), b = coarse.at<short>(y0, x1), c = coarse.at<short>(y1, x0),
                  e = coarse.at<short>(y1, x1);
      double raw;
      if (a > 0 && b > 0 && c > 0 && e > 0) {
        raw = (1 - fy) * ((1 - fx) * a + fx * b) + fy * ((1 - fx) * c + fx * e);
      } else {
        raw = coarse.at<short>(fy < 0.5 ? y0 : y1, fx < 0.5 ? x0 : x1);
      }
      out[u] = raw > 0 ? static_cast<int>(std::lround(2.0 * raw / 16.0)) : -1;
      d0f.at<float>(v, u) = static_cast<float>(2.0 * raw / 16.0);
    }
  });

  // Matching cost per pixel and offset: |dI| + |d(dI/du)| / 2 (the gradient term tolerates a gain or offset
  // between the units), summed over the block by a box filter. Offsets that leave the image cost the maximum.
  cv::Mat gxl, gxr;
  cv::Sobel(gl, gxl, CV_16S, 1, 0, 3);
  cv::Sobel(gr, gxr, CV_16S, 1, 0, 3);
  const int n = 2 * R + 1;
  std::vector<cv::Mat> cost(n);
  constexpr float kMax = 255.f * 3;
  tbb::parallel_for(0, n, [&](int k) {
    const int off = k - R;
    cv::Mat a(H, W, CV_32F);
    for (int v = 0; v < H; ++v) {
      const uint8_t* il = gl.ptr<uint8_t>(v);
      const uint8_t* ir = gr.ptr<uint8_t>(v);
      const short* sl = gxl.ptr<short>(v);
      const short* sr = gxr.ptr<short>(v);
      const int* dd = d0.ptr<int>(v);
      float* out = a.ptr<float>(v);
      for (int u = 0; u < W; ++u) {
        const int ur = u - dd[u] - off;
        out[u] = dd[u] < 0 || ur < 0 || ur >= W
                     ? kMax
                     : std::abs(int(il[u]) - int(ir[ur])) + 0.5f * std::abs(int(sl[u]) - int(sr[ur])) / 4.f;
      }
    }
    cv::boxFilter(a, cost[k], CV_32F, cv::Size(2 * half_bs + 1, 2 * half_bs + 1), cv::Point(-1, -1), false,
                  cv::BORDER_REPLICATE);
  });
  cv::Mat disp(H, W, CV_32F, cv::Scalar(-1));
  tbb::parallel_for(0, H, [&](int v) {
    const int* dd = d0.ptr<int>(v);
    float* out = disp.ptr<float>(v);
    for (int u = 0; u < W; ++u) {
      if (dd[u] < 0) continue;
      int best = 0;
      float bc = cost[0].ptr<float>(v)[u];
      for (int k = 1; k < n; ++k) {
        const float c = cost[k].ptr<float>(v)[u];
        if (c < bc) bc = c, best = k;
      }
      if (best == 0 || best == n - 1 || bc >= kMax) {
        // The block search disagrees with SGBM by more than its radius (a slanted or weakly textured patch,
        // where SGBM's smoothness is the better judge): keep the coarse disparity.
        out[u] = d0f.at<float>(v, u);
        continue;
      }
      const float cm = cost[best - 1].ptr<float>(v)[u], cp = cost[best + 1].ptr<float>(v)[u];
      const float den = cm - 2 * bc + cp;
      const float sub = den > 0 ? 0.5f * (cm - cp) / den : 0.f;
      const float d = static_cast<float>(dd[u] + best - R) + sub;
      if (d > 0) out[u] = d;
    }
  });
  return disp;
}

}  // namespace

double RangeFromDisparity(double baseline, double theta_left, double delta) {
  return baseline * std::sin(theta_left + delta) / std::sin(delta);
}

double RangeSigma(double baseline, double theta_left, double delta, double sigma_delta) {
  const double s = std::sin(delta);
  return baseline * std::sin(theta_left) / (s * s) * sigma_delta;
}

DenseDepth ComputeDenseDepth(const Rectification& r, const unwrap::Image8& left_rect, const unwrap::Image8& right_rect,
                             const DenseOptions& o) {
  o.Check("dense depth options");
  const int W = r.options.width, H = r.options.height;
  HOVS_REQUIRE(left_rect.width == W && left_rect.height == H && right_rect.width == W && right_rect.height == H,
               "dense depth", "rectified images must both be ", W, " x ", H, " (got ", left_rect.width, " x ",
               left_rect.height, " and ", right_rect.width, " x ", right_rect.height, ")");
  HOVS_REQUIRE(left_rect.channels == right_rect.channels, "dense depth", "rectified images differ in channels");
  HOVS_REQUIRE(o.num_disparities < W, "dense depth options", "num_disparities (", o.num_disparities,
               ") must be smaller than the rectified width (", W, ")");
  const auto start = std::chrono::steady_clock::now();
  const auto to_grey = [](const unwrap::Image8& im) {
    cv::Mat m(im.height, im.width, im.channels == 3 ? CV_8UC3 : CV_8UC1, const_cast<uint8_t*>(im.data.data()));
    cv::Mat g;
    if (im.channels == 3)
      cv::cvtColor(m, g, cv::COLOR_RGB2GRAY);
    else
      g = m.clone();
    return g;
  };
  const cv::Mat gl = to_grey(left_rect), gr = to_grey(right_rect);
  const auto m0 = std::chrono::steady_clock::now();
  cv::Mat disp;  // columns, float; <= 0: no match (OpenCV marks those negative) or infinitely far
  if (o.coarse_to_fine) {
    disp = MatchCoarseToFine(gl, gr, o);
  } else {
    MatchSgbm(gl, gr, o.num_disparities, o.block_size).convertTo(disp, CV_32F, 1.0 / 16);
  }
  DenseDepth d;
  d.match_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - m0).count();
  d.width = W, d.height = H;
  d.disparity.assign(size_t(W) * H, -1.f);
  d.range.assign(size_t(W) * H, NAN);
  d.sigma.assign(size_t(W) * H, NAN);
  d.valid.assign(size_t(W) * H, 0);
  const double min_theta = o.min_theta_deg * kDeg;
  tbb::parallel_for(0, H, [&](int v) {
    for (int u = 0; u < W; ++u) {
      const size_t k = size_t(v) * W + u;
      const double dcol = disp.at<float>(v, u);
      if (!(dcol > 0)) continue;
      d.disparity[k] = static_cast<float>(dcol);
      const double theta_l = r.ThetaAt(u), delta = dcol * r.dtheta;
      const double theta_r = theta_l + delta;
      if (theta_l < min_theta || theta_r > M_PI - min_theta) continue;  // near the baseline direction
      const double range = RangeFromDisparity(r.baseline, theta_l, delta);
      const double sigma = RangeSigma(r.baseline, theta_l, delta, o.sigma_disparity_px * r.dtheta);
      if (!(range > 0) || sigma > o.max_relative_sigma * range) continue;
      d.range[k] = static_cast<float>(range);
      d.sigma[k] = static_cast<float>(sigma);
      d.valid[k] = 1;
    }
  });
  d.total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return d;
}

void WritePly(const std::filesystem::path& path, const std::vector<ColouredPoint>& points) {
  std::ostringstream os;
  os << std::setprecision(9);  // every float exactly (the stream's default 6 digits rounded 12.34567 m to 0.1 mm)
  os << "ply\nformat ascii 1.0\ncomment hovs point cloud, left unit mirror frame, metres\nelement vertex "
     << points.size() << "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
     << "property uchar green\nproperty uchar blue\nend_header\n";
  for (const auto& p : points)
    os << float(p.p.x()) << ' ' << float(p.p.y()) << ' ' << float(p.p.z()) << ' ' << int(p.rgb[0]) << ' '
       << int(p.rgb[1]) << ' ' << int(p.rgb[2]) << '\n';
  WriteFileAtomic(path, os.str());
}

void WriteVtp(const std::filesystem::path& path, const std::vector<ColouredPoint>& points,
              const std::vector<float>& sigma) {
  HOVS_REQUIRE(sigma.empty() || sigma.size() == points.size(), path.string(), "sigma array size mismatch");
  const size_t n = points.size();
  std::ostringstream os;
  os << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
     << " <PolyData>\n  <Piece NumberOfPoints=\"" << n << "\" NumberOfVerts=\"" << n
     << "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n   <PointData Scalars=\"range\">\n"
     << "    <DataArray type=\"Float32\" Name=\"range\" format=\"ascii\">";
  for (const auto& p : points) os << float(p.p.norm()) << ' ';
  os << "</DataArray>\n";
  if (!sigma.empty()) {
    os << "    <DataArray type=\"Float32\" Name=\"sigma\" format=\"ascii\">";
    for (float s : sigma) os << s << ' ';
    os << "</DataArray>\n";
  }
  os << "    <DataArray type=\"UInt8\" Name=\"rgb\" NumberOfComponents=\"3\" format=\"ascii\">";
  for (const auto& p : points) os << int(p.rgb[0]) << ' ' << int(p.rgb[1]) << ' ' << int(p.rgb[2]) << ' ';
  os << "</DataArray>\n   </PointData>\n   <Points>\n    <DataArray type=\"Float32\" NumberOfComponents=\"3\" "
        "format=\"ascii\">";
  for (const auto& p : points) os << float(p.p.x()) << ' ' << float(p.p.y()) << ' ' << float(p.p.z()) << ' ';
  os << "</DataArray>\n   </Points>\n   <Verts>\n    <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">";
  for (size_t i = 0; i < n; ++i) os << i << ' ';
  os << "</DataArray>\n    <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">";
  for (size_t i = 0; i < n; ++i) os << i + 1 << ' ';
  os << "</DataArray>\n   </Verts>\n  </Piece>\n </PolyData>\n</VTKFile>\n";
  WriteFileAtomic(path, os.str());
}

void WriteRangeExr(const std::filesystem::path& path, const DenseDepth& d,
                   const std::vector<std::pair<std::string, std::string>>& metadata) {
  const size_t n = size_t(d.width) * d.height;
  std::vector<float> data(2 * n);
  for (size_t k = 0; k < n; ++k) data[2 * k] = d.range[k], data[2 * k + 1] = d.sigma[k];
  std::filesystem::create_directories(path.has_parent_path() ? path.parent_path() : std::filesystem::path("."));
  const auto tmp = path.parent_path() / ("." + path.filename().string() + ".tmp.exr");
  auto out = OIIO::ImageOutput::create(path.string());
  HOVS_REQUIRE(out != nullptr, path.string(), "no EXR writer: ", OIIO::geterror());
  OIIO::ImageSpec spec(d.width, d.height, 2, OIIO::TypeDesc::FLOAT);
  spec.channelnames = {"Z", "Z.sigma"};
  spec.attribute("compression", "zip");
  for (const auto& [k, v] : metadata) spec.attribute(k, v);
  const bool ok = out->open(tmp.string(), spec) && out->write_image(OIIO::TypeDesc::FLOAT, data.data()) && out->close();
  if (!ok) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw Error(path.string(), "cannot write EXR: " + out->geterror());
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace hovs::depth
