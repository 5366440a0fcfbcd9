// The optics layer against what must hold exactly: a vanishing aperture is the single-viewpoint projection, a
// spot at its own best focus is sharper than out of it, blur scales with the aperture, the slanted-edge MTF of
// a synthetic edge of known blur, the thin-lens formulas, and bad lenses refused.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/lens.h"
#include "core/yaml_reader.h"
#include "design/design.h"
#include "optics/focus.h"
#include "optics/slanted_edge.h"

namespace hovs::optics {
namespace {

OpticalSystem Reference(double f_number) {
  design::CameraSpec cam;
  OpticalSystem sys;
  sys.rig = design::RigOf({0.048, 0.044, 0.080}, cam);
  sys.lens.f_number = f_number;
  sys.pixel_pitch = cam.pixel_pitch;
  return sys;
}

TEST(Optics, AVanishingApertureIsTheSingleViewpointProjection) {
  const OpticalSystem sys = Reference(4);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> elev(-80, -2), az(-180, 180), dist(0.5, 500);
  for (int k = 0; k < 40; ++k) {
    const FieldPoint f{elev(rng), az(rng), dist(rng)};
    Vec2d uv;
    ASSERT_EQ(sys.rig.ImgFromMirror(f.Position(), &uv), ProjectionStatus::kOk);
    const Bundle b = TraceBundle(sys.rig, f.Position(), 1e-9, PupilPoints(256, 1e-9));
    ASSERT_EQ(b.size(), 256u);
    for (const double focus : {0.15, kInfinity}) {
      const Spot s = SpotAt(b, sys.rig.camera, focus);
      EXPECT_LT(s.rms, 0.01);
      EXPECT_LT((s.centroid - uv).norm(), 1e-6) << f.elevation_deg << " " << f.azimuth_deg << " " << f.distance;
    }
  }
}

TEST(Optics, ThePupilIsUniformByArea) {
  const std::vector<double> p = PupilPoints(4096, 2.0);
  int inner = 0;
  double cx = 0, cy = 0;
  for (size_t k = 0; k < p.size() / 2; ++k) {
    const double r = std::hypot(p[2 * k], p[2 * k + 1]);
    EXPECT_LE(r, 2.0);
    inner += r <= std::sqrt(2.0);  // half the area
    cx += p[2 * k], cy += p[2 * k + 1];
  }
  EXPECT_NEAR(inner, 2048, 4);
  EXPECT_NEAR(cx / 4096, 0, 1e-3);
  EXPECT_NEAR(cy / 4096, 0, 1e-3);
}

TEST(Optics, BestFocusIsSharperThanAnyOtherAndBlurScalesWithTheAperture) {
  const OpticalSystem f4 = Reference(4), f8 = Reference(8);
  const FieldPoint f{-40, 20, 3};
  const Bundle b4 =
      TraceBundle(f4.rig, f.Position(), f4.lens.ApertureRadius(), PupilPoints(256, f4.lens.ApertureRadius()));
  const Bundle b8 =
      TraceBundle(f8.rig, f.Position(), f8.lens.ApertureRadius(), PupilPoints(256, f8.lens.ApertureRadius()));
  const BestFocus best = BestFocusOf(f4, b4, 0.03);
  ASSERT_TRUE(std::isfinite(best.rms_focus));
  // The virtual image lies a little beyond the mirror (2c = 130 mm from the lens).
  EXPECT_GT(best.rms_focus, 0.12);
  EXPECT_LT(best.rms_focus, 0.20);
  for (const double d : {0.9 * best.rms_focus, 1.1 * best.rms_focus, 1.0})
    EXPECT_GT(SpotAt(b4, f4.CameraAt(d), d).rms, best.rms);
  // Defocus blur is proportional to the aperture: half the aperture, half the spot (to the second order).
  const double d = 1.2 * best.rms_focus;
  const double r4 = SpotAt(b4, f4.CameraAt(d), d).rms, r8 = SpotAt(b8, f8.CameraAt(d), d).rms;
  EXPECT_NEAR(r8 / r4, 0.5, 0.01);
  // A real lens: the image scale follows the focus, s = f d / (d - f).
  EXPECT_NEAR(f4.CameraAt(d).fx * f4.pixel_pitch, 0.016 * d / (d - 0.016), 1e-12);
}

TEST(Optics, TheSingleFocusBoundsEveryFieldPointAndTheDepthOfFieldHoldsTheLimit) {
  const OpticalSystem sys = Reference(8);
  const auto fields = FieldGrid(-80, -5, 8, DistanceGrid(1, 1e4, 4));
  const auto traced = TraceFields(sys, fields);
  const SingleFocus sf = BestSingleFocus(sys, traced, 0.03);
  double worst = 0;
  for (const auto& t : traced)
    worst = std::max(worst, SpotAt(t.bundle, sys.CameraAt(sf.focus_distance), sf.focus_distance).rms);
  EXPECT_NEAR(worst, sf.worst_rms, 1e-9);
  for (const double d : {0.95 * sf.focus_distance, 1.05 * sf.focus_distance}) {
    double w = 0;
    for (const auto& t : traced) w = std::max(w, SpotAt(t.bundle, sys.CameraAt(d), d).rms);
    EXPECT_GE(w, sf.worst_rms);
  }
  // Depth of focus: at its two ends the worst blur is the best's plus the tolerance; inside, within it.
  const auto worst_at = [&](double d) {
    double w = 0;
    for (const auto& t : traced) w = std::max(w, SpotAt(t.bundle, sys.CameraAt(d), d).rms);
    return w;
  };
  const DepthOfFocus dof_focus = DepthOfFocusOf(sys, traced, sf, 0.5, 0.03);
  ASSERT_LT(dof_focus.near_focus, sf.focus_distance);
  ASSERT_GT(dof_focus.far_focus, sf.focus_distance);
  ASSERT_TRUE(std::isfinite(dof_focus.far_focus));
  EXPECT_NEAR(worst_at(dof_focus.near_focus), sf.worst_rms + 0.5, 1e-6);
  EXPECT_NEAR(worst_at(dof_focus.far_focus), sf.worst_rms + 0.5, 1e-6);
  EXPECT_TRUE(dof_focus.Contains(sf.focus_distance));
  EXPECT_FALSE(dof_focus.Contains(0.99 * dof_focus.near_focus));
  EXPECT_LE(worst_at(0.5 * (dof_focus.near_focus + dof_focus.far_focus)), sf.worst_rms + 0.5);
  // Depth of field at one elevation, focused on its own best focus at 2 m: sharp there, blurred past the limits.
  const double e = -30;
  const Bundle b = TraceBundle(sys.rig, FieldPoint{e, 0, 2}.Position(), sys.lens.ApertureRadius(),
                               PupilPoints(256, sys.lens.ApertureRadius()));
  const double focus = BestFocusOf(sys, b, 0.03).rms_focus;
  const DepthOfField dof = DepthOfFieldAt(sys, e, focus, 0.1, 0.2);
  // (a tight 0.1 px limit: at f/8 the virtual image hardly moves with the scene distance, 1 px holds from 0.2 m)
  ASSERT_TRUE(dof.sharp);
  EXPECT_LT(dof.near, 2.0);
  EXPECT_GT(dof.far, 2.0);
  const auto rms_at = [&](double dist) {
    const Bundle x = TraceBundle(sys.rig, FieldPoint{e, 0, dist}.Position(), sys.lens.ApertureRadius(),
                                 PupilPoints(256, sys.lens.ApertureRadius()));
    return SpotAt(x, sys.CameraAt(focus), focus).rms;
  };
  EXPECT_GT(dof.near, 0.3);
  EXPECT_LE(rms_at(dof.near * 1.01), 0.1);
  EXPECT_GT(rms_at(dof.near * 0.97), 0.1) << dof.near;
  if (std::isfinite(dof.far)) EXPECT_GT(rms_at(dof.far * 1.05), 0.1);
}

TEST(Optics, DiffractionAndPixelMtfHaveTheirClosedForms) {
  // Cut-off at pitch / (lambda N): 4.54 um, 550 nm, f/4 -> 2.064 cycles / px.
  EXPECT_NEAR(DiffractionMtf(0, 4.54e-6, 550e-9, 4), 1.0, 1e-12);
  EXPECT_NEAR(DiffractionMtf(4.54e-6 / (550e-9 * 4), 4.54e-6, 550e-9, 4), 0.0, 1e-9);
  EXPECT_NEAR(DiffractionMtf(0.5 * 4.54e-6 / (550e-9 * 4), 4.54e-6, 550e-9, 4),
              2 / M_PI * (std::acos(0.5) - 0.5 * std::sqrt(0.75)), 1e-12);
  EXPECT_NEAR(PixelMtf(0.5), 2 / M_PI, 1e-12);
}

TEST(Optics, TheSlantedEdgeMeasuresTheMtfOfAKnownBlur) {
  // A 5 deg slanted edge, blurred by a Gaussian of sigma 1.5 px, box-integrated over each pixel (supersampled):
  // its MTF is exp(-2 (pi sigma nu)^2) sinc(nu cos) sinc(nu sin).
  const int w = 64, h = 64;
  const double sigma = 1.5, slope = std::tan(5 * M_PI / 180);
  std::vector<float> img(w * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double v = 0;
      for (int sy = 0; sy < 8; ++sy)
        for (int sx = 0; sx < 8; ++sx) {
          const double px = x - 0.5 + (sx + 0.5) / 8, py = y - 0.5 + (sy + 0.5) / 8;
          const double dist = (px - (32 + slope * (py - 32))) / std::sqrt(1 + slope * slope);
          v += 0.1 + 0.8 * 0.5 * std::erfc(-dist / (sigma * std::sqrt(2.0)));
        }
      img[y * w + x] = static_cast<float>(v / 64);
    }
  const EdgeMtf m = MeasureSlantedEdge(img, w, h, /*across_x=*/true);
  ASSERT_TRUE(m.ok);
  const Vec2d n = m.normal;
  const double expected = Mtf50([&](double nu) {
    return std::exp(-2 * std::pow(M_PI * sigma * nu, 2)) * PixelMtf(nu * n.x()) * PixelMtf(nu * n.y());
  });
  EXPECT_NEAR(m.mtf50, expected, 0.03 * expected);
  EXPECT_NEAR(std::abs(n.x()), std::cos(5 * M_PI / 180), 1e-3);
}

TEST(Optics, BadLensesAreRefusedNamingTheValue) {
  ThinLens lens;
  lens.f_number = 0;
  EXPECT_THROW(lens.Check("lens"), Error);
  lens = ThinLens{};
  lens.focus_distance = 0.01;  // inside the focal length
  try {
    lens.Check("lens");
    FAIL();
  } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find("focus_distance"), std::string::npos); }
  lens = ThinLens{};
  lens.f_number = std::nan("");
  EXPECT_THROW(lens.Check("lens"), Error);
  const YamlReader r("cfg.yaml");
  EXPECT_THROW(r.Lens(r.Load("{f_number: -2}"), "lens", 0.016), Error);
  EXPECT_THROW(r.Lens(r.Load("{f_number: 2, aperture_diameter: 0.004}"), "lens", 0.016), Error);
  EXPECT_THROW(r.Lens(r.Load("{focus_distance: .nan}"), "lens", 0.016), Error);
  EXPECT_THROW(r.Lens(r.Load("{focus_distance: 0.012}"), "lens", 0.016), Error);
  EXPECT_TRUE(std::isinf(r.Lens(r.Load("{focus_distance: infinity}"), "lens", 0.016).focus_distance));
  EXPECT_NEAR(r.Lens(r.Load("{aperture_diameter: 0.004}"), "lens", 0.016).f_number, 4.0, 1e-12);
}

}  // namespace
}  // namespace hovs::optics
