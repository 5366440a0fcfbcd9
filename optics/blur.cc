#include "optics/blur.h"

#include <algorithm>
#include <cmath>
#include <complex>

namespace hovs::optics {

Vec3d FieldPoint::Position() const {
  const double e = elevation_deg * M_PI / 180, a = azimuth_deg * M_PI / 180;
  return (std::isinf(distance) ? kFarDistance : distance) *
         Vec3d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
}

std::vector<double> PupilPoints(int n, double radius) {
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  std::vector<double> p(2 * static_cast<size_t>(std::max(n, 0)));
  for (int k = 0; k < n; ++k) {
    const double r = radius * std::sqrt((k + 0.5) / n), t = k * golden;
    p[2 * k] = r * std::cos(t), p[2 * k + 1] = r * std::sin(t);
  }
  return p;
}

Bundle TraceBundle(const CatadioptricCamera<double>& rig, const Vec3d& X, double aperture_radius,
                   const std::vector<double>& pupil) {
  Bundle b;
  const Vec3d C = rig.CameraCentre();
  const Eigen::Quaterniond cam_from_mirror = rig.cam_from_mirror.rotation;
  const Eigen::Quaterniond mirror_from_cam = cam_from_mirror.conjugate();
  Vec3d M0;
  const int n = aperture_radius > 0 ? static_cast<int>(pupil.size() / 2) : 1;
  b.pupil_samples = n;
  if (rig.SolveReflectionPointVia(X, C, &M0) != ProjectionStatus::kOk) {
    b.lost = n;
    return b;
  }
  b.lx.reserve(n), b.ly.reserve(n), b.tx.reserve(n), b.ty.reserve(n);
  Vec2d start = M0.head<2>();
  for (int k = 0; k < n; ++k) {
    const Vec3d l_cam = aperture_radius > 0 ? Vec3d(pupil[2 * k], pupil[2 * k + 1], 0) : Vec3d::Zero();
    const Vec3d L = C + mirror_from_cam * l_cam;
    Vec3d M = M0;
    if (aperture_radius > 0 && rig.SolveReflectionPointVia(X, L, &M, &start) != ProjectionStatus::kOk) {
      ++b.lost;
      continue;
    }
    const Vec3d w = cam_from_mirror * Vec3d(M - L);
    if (!(w.z() > 0)) {
      ++b.lost;
      continue;
    }
    start = M.head<2>();
    b.lx.push_back(l_cam.x()), b.ly.push_back(l_cam.y());
    b.tx.push_back(w.x() / w.z()), b.ty.push_back(w.y() / w.z());
  }
  return b;
}

Spot SpotAt(const Bundle& b, const PinholeCamera<double>& camera, double focus_distance, bool keep_points) {
  Spot s;
  const size_t n = b.size();
  s.rays = static_cast<int>(n);
  if (n == 0) return s;
  const double inv_d = std::isinf(focus_distance) ? 0.0 : 1.0 / focus_distance;
  std::vector<Vec2d> p(n);
  Vec2d sum = Vec2d::Zero();
  for (size_t i = 0; i < n; ++i) {
    p[i] =
        Vec2d(camera.cx + camera.fx * (b.lx[i] * inv_d + b.tx[i]), camera.cy + camera.fy * (b.ly[i] * inv_d + b.ty[i]));
    sum += p[i];
  }
  s.centroid = sum / double(n);
  const Vec2d off = s.centroid - Vec2d(camera.cx, camera.cy);
  if (off.norm() > 1e-9) s.radial_dir = off.normalized();
  const Vec2d t(-s.radial_dir.y(), s.radial_dir.x());
  double rr = 0, tt = 0;
  std::vector<double> r2(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec2d d = p[i] - s.centroid;
    const double a = d.dot(s.radial_dir), c = d.dot(t);
    rr += a * a, tt += c * c, r2[i] = a * a + c * c;
  }
  s.radial_rms = std::sqrt(rr / n), s.tangential_rms = std::sqrt(tt / n);
  s.rms = std::sqrt((rr + tt) / n);
  const size_t rank = static_cast<size_t>(std::ceil(0.8 * n)) - 1;
  std::nth_element(r2.begin(), r2.begin() + rank, r2.end());
  s.ee80 = std::sqrt(r2[rank]);
  if (keep_points) s.points = std::move(p);
  return s;
}

double GeometricMtf(const Spot& s, const Vec2d& dir, double nu) {
  // Needs the points; SpotAt keeps them on request.
  if (s.points.empty()) return 0;
  std::complex<double> sum = 0;
  for (const Vec2d& p : s.points) sum += std::polar(1.0, 2 * M_PI * nu * (p - s.centroid).dot(dir));
  return std::abs(sum) / double(s.points.size());
}

double DiffractionMtf(double nu, double pixel_pitch, double wavelength, double working_f_number) {
  const double nu_c = pixel_pitch / (wavelength * working_f_number);
  const double x = std::abs(nu) / nu_c;
  if (x >= 1) return 0;
  return 2 / M_PI * (std::acos(x) - x * std::sqrt(1 - x * x));
}

double PixelMtf(double nu) { return nu == 0 ? 1.0 : std::abs(std::sin(M_PI * nu) / (M_PI * nu)); }

double Mtf50(const std::function<double(double)>& mtf, double nu_max) {
  const int steps = 400;
  double prev_nu = 0, prev = mtf(0);
  for (int k = 1; k <= steps; ++k) {
    const double nu = nu_max * k / steps, m = mtf(nu);
    if (m <= 0.5) return prev_nu + (nu - prev_nu) * (prev - 0.5) / (prev - m);
    prev_nu = nu, prev = m;
  }
  return nu_max;
}

MtfFigures MtfAlong(const Spot& s, const Vec2d& dir, double pixel_pitch, double wavelength, double working_f_number) {
  MtfFigures out;
  const size_t n = s.points.size();
  if (n == 0) return out;
  constexpr int kSteps = 256, kNyquist = 128;
  constexpr double kStep = 1.0 / kSteps;
  // Per point the phase 2 pi nu x at nu = k kStep, advanced by a rotation of 2 pi kStep x per step.
  std::vector<double> c(n, 1.0), sn(n, 0.0), cr(n), sr(n);
  for (size_t i = 0; i < n; ++i) {
    const double x = (s.points[i] - s.centroid).dot(dir);
    cr[i] = std::cos(2 * M_PI * kStep * x), sr[i] = std::sin(2 * M_PI * kStep * x);
  }
  double prev = 1.0;
  bool crossed = false;
  out.mtf50 = 1.0;
  for (int k = 1; k <= kSteps; ++k) {
    double sc = 0, ss = 0;
    for (size_t i = 0; i < n; ++i) {
      const double c1 = c[i] * cr[i] - sn[i] * sr[i], s1 = sn[i] * cr[i] + c[i] * sr[i];
      c[i] = c1, sn[i] = s1, sc += c1, ss += s1;
    }
    const double nu = k * kStep;
    const double m =
        std::sqrt(sc * sc + ss * ss) / double(n) * DiffractionMtf(nu, pixel_pitch, wavelength, working_f_number);
    if (k == kNyquist) out.nyquist = m;
    if (!crossed && m <= 0.5) {
      crossed = true;
      out.mtf50 = nu - kStep + kStep * (prev - 0.5) / (prev - m);
    }
    if (crossed && k >= kNyquist) break;
    prev = m;
  }
  return out;
}

void OpticalSystem::Check(const std::string& where) const {
  lens.Check(where + " (lens)");
  HOVS_REQUIRE(std::isfinite(pixel_pitch) && pixel_pitch > 0, where, "pixel_pitch must be > 0");
  HOVS_REQUIRE(pupil_samples >= 1 && pupil_samples <= 1 << 20, where, "pupil samples must be in 1..2^20 (got ",
               pupil_samples, ")");
}

PinholeCamera<double> OpticalSystem::CameraAt(double focus_distance) const {
  PinholeCamera<double> cam = rig.camera;
  cam.fx = cam.fy = lens.SensorDistanceAt(focus_distance) / pixel_pitch;
  return cam;
}

FieldBlur BlurOf(const OpticalSystem& sys, const FieldPoint& f, const Bundle& b, double focus_distance,
                 bool keep_points) {
  FieldBlur out;
  out.field = f;
  out.focus_distance = focus_distance;
  out.rays = static_cast<int>(b.size()), out.lost = b.lost;
  Spot s = SpotAt(b, sys.CameraAt(focus_distance), focus_distance, /*keep_points=*/true);
  if (!s.Valid()) return out;
  const double nw = sys.lens.WorkingFNumberAt(focus_distance);
  const Vec2d t(-s.radial_dir.y(), s.radial_dir.x());
  const MtfFigures r = MtfAlong(s, s.radial_dir, sys.pixel_pitch, sys.lens.wavelength, nw);
  const MtfFigures g = MtfAlong(s, t, sys.pixel_pitch, sys.lens.wavelength, nw);
  out.mtf_nyquist_radial = r.nyquist, out.mtf_nyquist_tangential = g.nyquist;
  out.mtf50_radial = r.mtf50, out.mtf50_tangential = g.mtf50;
  if (!keep_points) s.points.clear();
  out.spot = std::move(s);
  return out;
}

FieldBlur BlurOf(const OpticalSystem& sys, const FieldPoint& f, double focus_distance, bool keep_points) {
  const Bundle b = TraceBundle(sys.rig, f.Position(), sys.lens.ApertureRadius(),
                               PupilPoints(sys.pupil_samples, sys.lens.ApertureRadius()));
  return BlurOf(sys, f, b, focus_distance, keep_points);
}

}  // namespace hovs::optics
