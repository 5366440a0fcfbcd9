// The polynomial (Taylor) model of Scaramuzza, as in OCamCalib, in hovs' frames.
//
//   pixel (u, v) -> OCamCalib's (row, col) = (v, u)
//   [row - cy; col - cx] = [[c, d], [e, 1]] * [p_r; p_c]          (affine: c, d, e; centre (cx, cy))
// The article (section 4.1.2) calls these R_eps = (c, d, e) and t_eps = the centre.
//   rho = sqrt(p_r^2 + p_c^2),  f(rho) = a0 + a2 rho^2 + ... + aN rho^N   (a1 = 0)
//   bearing (mirror frame: x along columns, y along rows, z towards the mirror) = normalise(p_c, p_r, f(rho))
// OCamCalib's cam2world returns (p_r, p_c, f(rho)): hovs swaps the first two components so that the frame is
// right-handed and matches the exact model's. a0 < 0: the image centre looks down, at the camera.
//
// world2cam: theta = atan2(z, |(x, y)|), rho = g(theta) with g the inverse fitted over the valid annulus
// [rho_min, rho_max]: a Chebyshev series in the normalised elevation (stable at any degree), and OCamCalib's
// monomial invpol for its file format. ImgFromCamFast uses g alone (its round trip error is recorded,
// inv_error_px, 0.01 px or better where a degree up to 40 reaches it); ImgFromCam refines rho with Newton on
// f(rho) |(x, y)| - z rho = 0 and is exact to rounding whatever g's accuracy.
//
// Decentering (hovs' extension, zero in OCamCalib's files): the sensor point p = (p_r, p_c) that the polynomial
// maps is displaced before the affine map by Brown-Conrady's tangential terms on (x, y) = (p_c, p_r) / |a0|
// (OpenCV's p1, p2 in the image's column and row directions):
//   x_d = x + 2 p1 x y + p2 (r^2 + 2 x^2),  y_d = y + p1 (r^2 + 2 y^2) + 2 p2 x y
// A lens or a camera not quite on the mirror's axis decentres the image this way; the unified model's radtan
// holds the same terms. rho is always the radius of the undecentred point (RhoOfImg).
//
// Parameters, in order: cx, cy, c, d, e, a0, a1 (held at 0), a2, ..., aN[, p1, p2].
// Valid domain: rho_min <= rho <= rho_max, where theta(rho) = atan2(f(rho), rho) is monotonic.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "core/distortion.h"
#include "core/error.h"
#include "core/model_check.h"
#include "core/newton.h"
#include "core/types.h"

namespace hovs {

template <class T>
struct PolynomialModel {
  int width = 0, height = 0;
  T cx = T(0), cy = T(0);          // centre: column, row (pixels)
  T c = T(1), d = T(0), e = T(0);  // affine
  T p1 = T(0), p2 = T(0);          // decentering (zero: OCamCalib's model)
  std::vector<T> poly;             // a0, a1 (= 0), a2, ..., aN
  std::vector<double> inv_poly;    // OCamCalib's invpol: rho = sum inv_poly[i] theta^i
  std::vector<double> inv_cheb;    // rho = sum inv_cheb[i] T_i(t), t = theta mapped from [inv_theta_lo, hi] to [-1, 1]
  double inv_theta_lo = 0, inv_theta_hi = 0;
  double inv_error_px = 0, inv_poly_error_px = 0;  // worst round trip of each inverse over the annulus (pixels)
  double rho_min = 0, rho_max = 0;                 // valid annulus (pixels, in the affine-corrected plane)

  int Degree() const { return static_cast<int>(poly.size()) - 1; }

  template <class S>
  S F(const S& rho) const {
    S acc = S(0);
    for (int i = Degree(); i >= 0; --i) acc = acc * rho + ConvertScalar<S>(poly[i]);
    return acc;
  }

  // Affine-corrected sensor coordinates (p_r, p_c) of pixel uv.
  Vec2<T> SensorFromImg(const Vec2<T>& uv) const {
    const T dr = uv(1) - cy, dc = uv(0) - cx;
    const T inv_det = T(1) / (c - d * e);
    return Vec2<T>(inv_det * (dr - d * dc), inv_det * (-e * dr + c * dc));
  }
  Vec2<T> ImgFromSensor(const Vec2<T>& p) const {
    const T row = c * p(0) + d * p(1) + cy;
    const T col = e * p(0) + p(1) + cx;
    return Vec2<T>(col, row);
  }

  // Jets always take the decentering path, so that derivatives with respect to p1 and p2 exist at zero too.
  bool HasDecentering() const {
    if constexpr (std::is_same_v<T, double>) return p1 != 0 || p2 != 0;
    return true;
  }

  // The displaced sensor point of p (Decenter) and its inverse (Recenter: Newton; false where it fails).
  Vec2<T> Decenter(const Vec2<T>& p) const {
    if (!HasDecentering()) return p;
    const T s = ScalarPart(poly[0]) < 0 ? T(-poly[0]) : T(poly[0]);
    const Vec2<T> moved = Decentering().Distort(Vec2<T>(p(1) / s, p(0) / s));
    return Vec2<T>(moved(1) * s, moved(0) * s);
  }
  bool Recenter(const Vec2<T>& q, Vec2<T>* p) const {
    if (!HasDecentering()) {
      *p = q;
      return true;
    }
    const T s = ScalarPart(poly[0]) < 0 ? T(-poly[0]) : T(poly[0]);
    Vec2<T> m;
    if (!Decentering().Undistort(Vec2<T>(q(1) / s, q(0) / s), &m)) return false;
    *p = Vec2<T>(m(1) * s, m(0) * s);
    return true;
  }
  // rho of pixel uv (NaN where the decentering cannot be undone).
  T RhoOfImg(const Vec2<T>& uv) const {
    using std::sqrt;
    Vec2<T> p;
    if (!Recenter(SensorFromImg(uv), &p)) return T(std::numeric_limits<double>::quiet_NaN());
    return sqrt(p.squaredNorm());
  }

  bool CamFromImg(const Vec2<T>& uv, Vec3<T>* bearing) const {
    using std::sqrt;
    Vec2<T> p;
    if (!Recenter(SensorFromImg(uv), &p)) return false;
    const T r2 = p.squaredNorm();
    const T rho = ScalarPart(r2) > 0 ? sqrt(r2) : T(0);
    *bearing = Normalized<T>(Vec3<T>(p(1), p(0), F(rho)));
    return std::isfinite(ScalarPart((*bearing)(2)));
  }

  // Exact inverse of CamFromImg (Newton on rho from the inverse polynomial's estimate, or from rho_hint when
  // it is given: e.g. the observed pixel's radius during calibration, when no inverse polynomial exists yet).
  bool ImgFromCam(const Vec3<T>& X, Vec2<T>* uv, double rho_hint = -1) const {
    using std::sqrt;
    const double xd = ScalarPart(X(0)), yd = ScalarPart(X(1)), zd = ScalarPart(X(2));
    const double nd = std::sqrt(xd * xd + yd * yd);  // not hypot (slower; bearings are far from overflow)
    if (nd == 0) {
      if (!(zd * ScalarPart(poly[0]) > 0)) return false;
      *uv = ImgFromSensor(Decenter(Vec2<T>(T(0), T(0))));
      return true;
    }
    double rho = rho_hint >= 0 ? rho_hint : EstimateRho(std::atan2(zd, nd));
    if constexpr (std::is_same_v<T, double>) {
      if (!RhoByNewton(nd, zd, &rho)) return false;
      *uv = ImgFromSensor(Decenter(Vec2<T>(yd / nd * rho, xd / nd * rho)));
      return true;
    }
    const auto h = [&](const auto& r) { return F(r) * nd - zd * r; };
    NewtonOptions options;
    options.residual_tolerance = 1e-13 * (std::abs(ScalarPart(poly[0])) * nd + 1e-300);
    options.max_step = std::max(1.0, 0.1 * rho_max);
    double dh = 0;
    if (!SolveNewton1(h, &rho, &dh, options) || !(rho >= 0)) return false;
    const T n = sqrt(X(0) * X(0) + X(1) * X(1));
    const auto h_t = [&](const T& r) { return F(r) * n - X(2) * r; };
    const T rho_t = LiftNewton1<T>(h_t, rho, dh);
    *uv = ImgFromSensor(Decenter(Vec2<T>(X(1) / n * rho_t, X(0) / n * rho_t)));
    return true;
  }

  // ImgFromCam of `count` points at once (T = double; X and uv row-major, count x 3 and count x 2; ok[i] as
  // ImgFromCam returns). The same start and Newton iteration, run on blocks of points with the points innermost,
  // so that the Chebyshev and Horner passes vectorise and the points' dependency chains overlap instead of one
  // point's latency following the other's. A point the block cannot settle (on the axis, not finite, a failed or
  // unconverged iteration, no Chebyshev inverse) takes ImgFromCam itself. Agrees with ImgFromCam to rounding.
  void ImgFromCamBatch(const double* X, std::size_t count, double* uv, bool* ok) const {
    static_assert(std::is_same_v<T, double>, "ImgFromCamBatch works on a double model");
    constexpr int kLanes = 16;
    const bool chebyshev = !inv_cheb.empty() && inv_theta_hi > inv_theta_lo;
    const int degree = Degree(), terms = static_cast<int>(inv_cheb.size());
    const double mid = 0.5 * (inv_theta_lo + inv_theta_hi), inv_half = 2.0 / (inv_theta_hi - inv_theta_lo);
    const double tolerance_scale = 1e-13 * std::abs(poly[0]), max_step = std::max(1.0, 0.1 * rho_max);
    alignas(64) double nd[kLanes], zd[kLanes], r[kLanes], t[kLanes], b1[kLanes], b2[kLanes], active[kLanes];
    bool slow[kLanes];
    for (std::size_t base = 0; base < count; base += kLanes) {
      const int m = static_cast<int>(std::min<std::size_t>(kLanes, count - base));
      const double* x = X + 3 * base;
      for (int l = 0; l < kLanes; ++l) {
        const int k = l < m ? l : 0;  // padding lanes repeat the first point and are never written
        const double xd = x[3 * k], yd = x[3 * k + 1];
        nd[l] = std::sqrt(xd * xd + yd * yd), zd[l] = x[3 * k + 2];
        slow[l] = !chebyshev || !(nd[l] > 0) || !std::isfinite(nd[l]) || !std::isfinite(zd[l]);
        t[l] = slow[l] ? 0.0 : (std::atan2(zd[l], nd[l]) - mid) * inv_half;
        b1[l] = 0, b2[l] = 0, active[l] = l < m && !slow[l] ? 1.0 : 0.0;
      }
      if (chebyshev) {  // Clenshaw, as InverseRho
        for (int k = terms - 1; k >= 1; --k)
          for (int l = 0; l < kLanes; ++l) {
            const double b0 = 2 * t[l] * b1[l] - b2[l] + inv_cheb[k];
            b2[l] = b1[l], b1[l] = b0;
          }
        for (int l = 0; l < kLanes; ++l) {
          r[l] = t[l] * b1[l] - b2[l] + inv_cheb[0];
          if (!(r[l] >= 0) || !std::isfinite(r[l])) slow[l] = true, active[l] = 0, r[l] = 0;
        }
      }
      // Newton as RhoByNewton; a lane stops moving (active 0) once its residual or its step is at rounding.
      for (int it = 0; it < 50; ++it) {
        double any = 0;
        for (int l = 0; l < kLanes; ++l) {
          double f = 0, df = 0;
          for (int i = degree; i >= 0; --i) df = df * r[l] + f, f = f * r[l] + poly[i];
          const double h = f * nd[l] - zd[l] * r[l], dh = df * nd[l] - zd[l];
          const double step = std::clamp(-h / dh, -max_step, max_step);
          const bool bad = !(std::abs(h) < HUGE_VAL) || !(std::abs(dh) > 0 && std::abs(dh) < HUGE_VAL);
          const bool done = std::abs(h) <= tolerance_scale * nd[l] + 1e-313 ||
                            std::abs(step) <= 1e-15 * (std::abs(r[l] + step) + 1.0);
          r[l] += bad ? 0.0 : active[l] * step;
          slow[l] = slow[l] || (active[l] != 0 && bad);
          active[l] = bad || done ? 0.0 : active[l];
          any += active[l];
        }
        if (any == 0) break;
      }
      for (int l = 0; l < m; ++l) {
        double* q = uv + 2 * (base + l);
        const double* p = x + 3 * l;
        if (slow[l] || active[l] != 0) {
          Vec2<T> pixel;
          ok[base + l] = ImgFromCam(Vec3<T>(p[0], p[1], p[2]), &pixel);
          q[0] = pixel(0), q[1] = pixel(1);
          continue;
        }
        ok[base + l] = r[l] >= 0;
        const Vec2<T> pixel = ImgFromSensor(Decenter(Vec2<T>(p[1] / nd[l] * r[l], p[0] / nd[l] * r[l])));
        q[0] = pixel(0), q[1] = pixel(1);
      }
    }
  }

  // OCamCalib's world2cam: the fitted inverse only (no refinement; within inv_error_px of ImgFromCam).
  bool ImgFromCamFast(const Vec3<T>& X, Vec2<T>* uv) const {
    using std::atan2;
    using std::sqrt;
    const T n = sqrt(X(0) * X(0) + X(1) * X(1));
    if (ScalarPart(n) == 0) {
      *uv = ImgFromSensor(Decenter(Vec2<T>(T(0), T(0))));
      return true;
    }
    const T rho = InverseRho(atan2(X(2), n));
    *uv = ImgFromSensor(Decenter(Vec2<T>(X(1) / n * rho, X(0) / n * rho)));
    return true;
  }

  // Fits the inverse over [rho_min, rho_max]: a Chebyshev series in theta normalised to the annulus' elevation
  // range (inv_cheb, stable at any degree; the starting point of ImgFromCam's Newton and what ImgFromCamFast
  // evaluates), and OCamCalib's monomial invpol in raw theta (inv_poly, for calib_results.txt). Each takes the
  // lowest degree whose worst round trip is below max_error_px; where none is, the most accurate one is kept and
  // its error recorded (inv_error_px, inv_poly_error_px): ImgFromCam stays exact either way. Returns
  // inv_error_px. Throws only when theta(rho) is not monotonic over the annulus (no inverse exists).
  double FitInverse(double max_error_px = 0.01, int max_degree = 40) {
    static_assert(std::is_same_v<T, double>, "FitInverse works on a double model");
    HOVS_REQUIRE(rho_max > rho_min && rho_min >= 0, "polynomial model", "invalid annulus [", rho_min, ", ", rho_max,
                 "]");
    const int n = 2000;
    std::vector<double> theta(n), rho(n);
    for (int i = 0; i < n; ++i) {
      rho[i] = rho_min + (rho_max - rho_min) * i / (n - 1);
      theta[i] = std::atan2(F(rho[i]), rho[i]);
    }
    HOVS_REQUIRE(MonotonicOver(rho_min, rho_max), "polynomial model", "theta(rho) is not monotonic over [", rho_min,
                 ", ", rho_max, "] px: no inverse exists");
    // Pixel errors: rho errors scaled by the affine map's largest singular value.
    Eigen::Matrix2d A;
    A << c, d, e, 1;
    const double scale = Eigen::JacobiSVD<Eigen::Matrix2d>(A).singularValues()(0);
    const Eigen::Map<const Eigen::VectorXd> b(rho.data(), n);
    const auto fit = [&](const auto& basis, int deg, std::vector<double>* coef) {
      Eigen::MatrixXd V(n, deg + 1);
      for (int i = 0; i < n; ++i) basis(theta[i], deg, &V(i, 0), V.outerStride());
      const Eigen::VectorXd x = V.colPivHouseholderQr().solve(b);
      coef->assign(x.data(), x.data() + x.size());
      const double err = (V * x - b).cwiseAbs().maxCoeff() * scale;
      return std::isfinite(err) ? err : HUGE_VAL;
    };
    const auto best_fit = [&](const auto& basis, int max_deg, std::vector<double>* out) {
      double best = HUGE_VAL;
      std::vector<double> coef;
      for (int deg = 2; deg <= max_deg; ++deg) {
        const double err = fit(basis, deg, &coef);
        if (err < best) best = err, *out = coef;
        if (best < max_error_px) break;
      }
      return best;
    };
    inv_theta_lo = std::min(theta.front(), theta.back());
    inv_theta_hi = std::max(theta.front(), theta.back());
    const double mid = 0.5 * (inv_theta_lo + inv_theta_hi), half = 0.5 * (inv_theta_hi - inv_theta_lo);
    const auto chebyshev = [&](double th, int deg, double* row, Eigen::Index stride) {
      const double t = (th - mid) / half;
      double t0 = 1, t1 = t;
      row[0] = 1;
      if (deg >= 1) row[stride] = t;
      for (int k = 2; k <= deg; ++k) {
        const double t2 = 2 * t * t1 - t0;
        row[k * stride] = t2, t0 = t1, t1 = t2;
      }
    };
    const auto monomial = [](double th, int deg, double* row, Eigen::Index stride) {
      double p = 1;
      for (int k = 0; k <= deg; ++k, p *= th) row[k * stride] = p;
    };
    inv_error_px = best_fit(chebyshev, max_degree, &inv_cheb);
    inv_poly_error_px = best_fit(monomial, std::min(max_degree, 24), &inv_poly);
    return inv_error_px;
  }

  // True if theta(rho) is strictly monotonic over [lo, hi] with |dtheta/drho| >= min_slope (rad/px), sampled
  // every half pixel at most.
  bool MonotonicOver(double lo, double hi, double min_slope = 0) const {
    const int n = std::clamp(static_cast<int>(2 * (hi - lo)), 64, 100000);
    const double dr = (hi - lo) / n;
    double prev = std::atan2(ScalarPart(F(T(lo))), lo), sign = 0;
    for (int i = 1; i <= n; ++i) {
      const double r = lo + dr * i, th = std::atan2(ScalarPart(F(T(r))), r);
      const double step = th - prev;
      if (!(std::abs(step) > min_slope * dr) || (sign != 0 && step * sign < 0)) return false;
      sign = step > 0 ? 1 : -1, prev = th;
    }
    return true;
  }

  // Sets the annulus to [lo, hi] widened by up to the margins where theta(rho) stays monotonic and not flatter
  // than a quarter of its flattest slope over [lo, hi] (a low-degree fit can fold just past the data, and
  // where theta is nearly flat a pixel's elevation is ill-defined). Returns false, leaving the annulus
  // unchanged, when theta is not monotonic over [lo, hi] itself.
  bool SetAnnulusWithin(double lo, double hi, double margin_lo, double margin_hi) {
    if (!(hi > lo && lo >= 0) || !MonotonicOver(lo, hi)) return false;
    double flattest = HUGE_VAL;
    for (int i = 0; i < 256; ++i) {
      const double r0 = lo + (hi - lo) * i / 256, r1 = lo + (hi - lo) * (i + 1) / 256;
      flattest = std::min(
          flattest, std::abs(std::atan2(ScalarPart(F(T(r1))), r1) - std::atan2(ScalarPart(F(T(r0))), r0)) / (r1 - r0));
    }
    const auto widen = [&](double from, double limit) {
      double best = from;
      for (int k = 1; k <= 32; ++k) {
        const double to = from + (limit - from) * k / 32;
        if (!MonotonicOver(std::min(from, to), std::max(from, to), 0.25 * flattest)) break;
        best = to;
      }
      return best;
    };
    rho_max = widen(hi, hi + margin_hi);
    rho_min = widen(lo, std::max(0.0, lo - margin_lo));
    return true;
  }

  // Throws hovs::Error(where) for a model that cannot be a camera: non-finite or absurd numbers, a centre far
  // outside the image, a0 = 0 (every pixel would look sideways), an annulus where f is not finite.
  void Check(const std::string& where = "polynomial model") const {
    HOVS_REQUIRE(poly.size() >= 2 && poly.size() <= 21, where, "needs a0, a1 and at most degree 20 (got ", poly.size(),
                 " coefficients)");
    for (const auto& a : poly) HOVS_REQUIRE(std::isfinite(ScalarPart(a)), where, "coefficients must be finite");
    HOVS_REQUIRE(ScalarPart(poly[1]) == 0, where, "a1 must be 0 (got ", ScalarPart(poly[1]), ")");
    HOVS_REQUIRE(ScalarPart(poly[0]) != 0 && std::abs(ScalarPart(poly[0])) <= kMaxFocalPx, where,
                 "a0 must be non-zero and at most ", kMaxFocalPx, " px in size (got ", ScalarPart(poly[0]), ")");
    for (const T& v : {c, d, e})
      HOVS_REQUIRE(std::isfinite(ScalarPart(v)) && std::abs(ScalarPart(v)) <= 10, where,
                   "the affine terms c, d, e must be finite and within +-10 (c is about 1; got ", ScalarPart(v), ")");
    HOVS_REQUIRE(std::abs(ScalarPart(c - d * e)) >= 0.1, where, "the affine matrix is (nearly) singular");
    for (const T& v : {p1, p2})
      HOVS_REQUIRE(std::isfinite(ScalarPart(v)) && std::abs(ScalarPart(v)) <= 0.1, where,
                   "the decentering terms p1, p2 must be finite and within +-0.1 (got ", ScalarPart(v), ")");
    CheckImageAndCentre(width, height, ScalarPart(cx), ScalarPart(cy), where);
    HOVS_REQUIRE(inv_poly.size() <= 64, where, "the inverse polynomial has ", inv_poly.size(),
                 " coefficients (at most 64)");
    HOVS_REQUIRE(inv_cheb.size() <= 64, where, "the Chebyshev inverse has ", inv_cheb.size(),
                 " coefficients (at most 64)");
    for (double a : inv_poly) HOVS_REQUIRE(std::isfinite(a), where, "inverse polynomial coefficients must be finite");
    for (double a : inv_cheb) HOVS_REQUIRE(std::isfinite(a), where, "Chebyshev inverse coefficients must be finite");
    HOVS_REQUIRE(inv_cheb.empty() || (std::isfinite(inv_theta_lo) && std::isfinite(inv_theta_hi) &&
                                      inv_theta_lo < inv_theta_hi && inv_theta_lo >= -M_PI && inv_theta_hi <= M_PI),
                 where, "the Chebyshev inverse needs an elevation range -pi <= lo < hi <= pi");
    HOVS_REQUIRE(std::isfinite(rho_min) && std::isfinite(rho_max) && rho_min >= 0 && rho_max >= rho_min &&
                     (width == 0 || rho_max <= 2.0 * (width + height)),
                 where, "the annulus [", rho_min, ", ", rho_max, "] px does not fit the image");
    for (int k = 0; k <= 16 && rho_max > 0; ++k) {
      const double rho = rho_max * k / 16;
      HOVS_REQUIRE(std::isfinite(ScalarPart(F(T(rho)))), where, "f(rho) is not finite at rho = ", rho, " px");
    }
  }

  template <class U>
  PolynomialModel<U> Cast() const {
    PolynomialModel<U> m;
    m.width = width, m.height = height;
    m.cx = ConvertScalar<U>(cx), m.cy = ConvertScalar<U>(cy);
    m.c = ConvertScalar<U>(c), m.d = ConvertScalar<U>(d), m.e = ConvertScalar<U>(e);
    m.p1 = ConvertScalar<U>(p1), m.p2 = ConvertScalar<U>(p2);
    for (const auto& a : poly) m.poly.push_back(ConvertScalar<U>(a));
    m.inv_poly = inv_poly, m.inv_cheb = inv_cheb;
    m.inv_theta_lo = inv_theta_lo, m.inv_theta_hi = inv_theta_hi;
    m.inv_error_px = inv_error_px, m.inv_poly_error_px = inv_poly_error_px;
    m.rho_min = rho_min, m.rho_max = rho_max;
    return m;
  }

 private:
  // rho(theta) from the Chebyshev inverse (Clenshaw), else OCamCalib's monomial one.
  template <class S>
  S InverseRho(const S& theta) const {
    if (!inv_cheb.empty() && inv_theta_hi > inv_theta_lo) {
      const double mid = 0.5 * (inv_theta_lo + inv_theta_hi), half = 0.5 * (inv_theta_hi - inv_theta_lo);
      const S t = (theta - S(mid)) / S(half);
      S b1 = S(0), b2 = S(0);
      for (int k = static_cast<int>(inv_cheb.size()) - 1; k >= 1; --k) {
        const S b0 = S(2) * t * b1 - b2 + S(inv_cheb[k]);
        b2 = b1, b1 = b0;
      }
      return t * b1 - b2 + S(inv_cheb[0]);
    }
    S rho = S(0);
    for (int i = static_cast<int>(inv_poly.size()) - 1; i >= 0; --i) rho = rho * theta + S(inv_poly[i]);
    return rho;
  }

  RadTanDistortion<T> Decentering() const {
    RadTanDistortion<T> tangential;
    tangential.p1 = p1, tangential.p2 = p2;
    return tangential;
  }

  // ImgFromCam's Newton iteration on h(rho) = f(rho) |(x, y)| - z rho for T = double: the same tolerances and
  // damping as SolveNewton1 followed by LiftNewton1's polishing step, with f and f' from one Horner pass instead
  // of jets. Projection of many points (the Python module, mapping tables) spends its time here.
  bool RhoByNewton(double nd, double zd, double* rho) const {
    const double tolerance = 1e-13 * (std::abs(ScalarPart(poly[0])) * nd + 1e-300);
    const double max_step = std::max(1.0, 0.1 * rho_max);
    double r = *rho, h = 0;
    for (int it = 0; it < 50; ++it) {
      double f = 0, df = 0;
      for (int i = Degree(); i >= 0; --i) df = df * r + f, f = f * r + ScalarPart(poly[i]);
      h = f * nd - zd * r;
      const double dh = df * nd - zd;
      if (!std::isfinite(h) || !std::isfinite(dh) || dh == 0.0) return false;
      double step = -h / dh;
      if (std::abs(step) > max_step) step = std::copysign(max_step, step);
      r += step;
      // Converged: the residual is at rounding or the step is; the step just taken is the polish.
      if (std::abs(h) <= tolerance || std::abs(step) <= 1e-15 * (std::abs(r) + 1.0)) {
        *rho = r;
        return r >= 0;
      }
    }
    return false;
  }

  // Starting rho for Newton: the fitted inverse if there is one, else a bracketed search over the annulus.
  double EstimateRho(double theta) const {
    if (!inv_cheb.empty() || !inv_poly.empty()) {
      const double r = InverseRho(theta);
      if (std::isfinite(r) && r >= 0) return r;
    }
    const double hi = rho_max > 0 ? rho_max : 1000.0;
    double best = hi * 0.5, best_err = HUGE_VAL;
    for (int i = 0; i <= 64; ++i) {
      const double r = rho_min + (hi - rho_min) * i / 64.0;
      const double err = std::abs(std::atan2(ScalarPart(F(r)), r) - theta);
      if (err < best_err) best_err = err, best = r;
    }
    return best;
  }
};

}  // namespace hovs
