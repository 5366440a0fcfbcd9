#include "depth/article_depth.h"

#include <cmath>

#include "core/error.h"
#include "core/format.h"

namespace hovs::depth {
namespace {
constexpr double kDeg = M_PI / 180;
}  // namespace

ClosedFormDepth ArticleClosedForm(double baseline, const Vec3d& bl, const Vec3d& br) {
  ClosedFormDepth out;
  const double phi1 = std::atan2(bl.y(), bl.x()), phi2 = std::atan2(br.y(), br.x());
  const double s = std::sin(phi2 - phi1);
  const double h1 = bl.head<2>().norm();
  if (!(std::abs(s) > 1e-9) || !(h1 > 0)) return out;
  const double r1 = baseline * std::sin(phi2) / s;
  if (!(r1 > 0)) return out;
  const double z1 = r1 * bl.z() / h1;  // r_1 tan(el_1)
  out.point_left = Vec3d(r1 * std::cos(phi1), r1 * std::sin(phi1), z1);
  out.ok = true;
  return out;
}

void DepthFormulaOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(!ranges_m.empty() && !elevations_deg.empty(), where, "needs ranges and elevations");
  for (double r : ranges_m) HOVS_REQUIRE(r > 0 && std::isfinite(r), where, "ranges must be positive");
  for (double e : elevations_deg) HOVS_REQUIRE(std::abs(e) < 90, where, "elevations must lie in (-90, 90) degrees");
  HOVS_REQUIRE(azimuth_step_deg > 0 && azimuth_step_deg <= 90, where, "the azimuth step must be in (0, 90] degrees");
  HOVS_REQUIRE(min_angle_to_baseline_deg >= 0 && min_angle_to_baseline_deg < 90, where,
               "the smallest angle to the baseline must be in [0, 90) degrees");
}

DepthFormulaStudy CompareDepthFormulas(const StereoRig& rig, const DepthFormulaOptions& o) {
  o.Check("depth formula study");
  DepthFormulaStudy study;
  study.methods = {"article, each unit's own azimuths", "article, bearings turned into the left frame",
                   "hovs, rays from F1 with the full pose", "hovs, each unit's own rays"};
  const double b = rig.Baseline();
  const Mat3<double> left_from_right = rig.right_from_left.rotation.conjugate().toRotationMatrix();
  // The baseline's direction in the left frame: azimuths and angles to the baseline are measured from it.
  const Vec3d base = rig.RightCentreInLeft().normalized();
  const double base_az = std::atan2(base.y(), base.x());
  const std::vector<double> angle_edges = {0, 30, 60, 120, 150, 180};
  const size_t M = study.methods.size();
  std::vector<std::vector<std::vector<double>>> by_range(o.ranges_m.size(), std::vector<std::vector<double>>(M)),
      by_angle(angle_edges.size() - 1, std::vector<std::vector<double>>(M));
  for (size_t ri = 0; ri < o.ranges_m.size(); ++ri)
    for (double el_deg : o.elevations_deg)
      for (double a = -180 + o.azimuth_step_deg; a < 180; a += o.azimuth_step_deg) {
        const double angle = std::abs(a);  // angle to the baseline in the horizontal plane
        if (angle < o.min_angle_to_baseline_deg || angle > 180 - o.min_angle_to_baseline_deg) continue;
        const double r = o.ranges_m[ri], el = el_deg * kDeg, az = base_az + a * kDeg;
        const Vec3d p = r * Vec3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
        Vec2d ul, ur;
        if (!rig.left.ImgFromPointUnbounded(p, &ul) || !rig.right.ImgFromPointUnbounded(rig.right_from_left * p, &ur))
          continue;
        Vec3d bl, br, ol, dl, orr, dr;
        if (!rig.left.MirrorFromImg(ul, &bl) || !rig.right.MirrorFromImg(ur, &br) ||
            !rig.left.RayFromImg(ul, &ol, &dl) || !rig.right.RayFromImg(ur, &orr, &dr))
          continue;
        const ClosedFormDepth own = ArticleClosedForm(b, bl, br),
                              turned = ArticleClosedForm(b, bl, left_from_right * br);
        const Triangulation central = Triangulate(rig, bl, br, 0), rays = Triangulate(rig, ol, dl, orr, dr, 0);
        if (!own.ok || !turned.ok || !central.ok || !rays.ok) continue;
        const double e[4] = {(own.point_left - p).norm() / r, (turned.point_left - p).norm() / r,
                             (central.point_left - p).norm() / r, (rays.point_left - p).norm() / r};
        size_t bin = 0;
        while (bin + 2 < angle_edges.size() && angle >= angle_edges[bin + 1]) ++bin;
        for (size_t m = 0; m < M; ++m) by_range[ri][m].push_back(e[m]), by_angle[bin][m].push_back(e[m]);
        ++study.points;
      }
  HOVS_REQUIRE(study.points > 0, "depth formula study", "no point is seen by both units");
  for (size_t ri = 0; ri < o.ranges_m.size(); ++ri) {
    DepthFormulaBin bin{FormatNumber("%g", o.ranges_m[ri]) + " m", {}};
    for (size_t m = 0; m < M; ++m) bin.methods.push_back(Summarise(by_range[ri][m]));
    study.by_range.push_back(bin);
  }
  for (size_t k = 0; k + 1 < angle_edges.size(); ++k) {
    const double lo = std::max(angle_edges[k], o.min_angle_to_baseline_deg),
                 hi = std::min(angle_edges[k + 1], 180 - o.min_angle_to_baseline_deg);
    DepthFormulaBin bin{FormatNumber("%g", lo) + "-" + FormatNumber("%g", hi) + " deg", {}};
    for (size_t m = 0; m < M; ++m) bin.methods.push_back(Summarise(by_angle[k][m]));
    study.by_angle.push_back(bin);
  }
  return study;
}

std::string DepthFormulaMarkdown(const DepthFormulaStudy& s) {
  const auto table = [&](const std::string& first, const std::vector<DepthFormulaBin>& bins) {
    std::string t = "| " + first + " | points |";
    for (const auto& m : s.methods) t += " " + m + " |";
    t += "\n| --- | --- |";
    for (size_t m = 0; m < s.methods.size(); ++m) t += " --- |";
    t += "\n";
    for (const auto& b : bins) {
      t += "| " + b.name + " | " + std::to_string(b.methods[0].count) + " |";
      for (const auto& m : b.methods)
        t += " " + FormatNumber("%.3g", 100 * m.median) + " % (95 %: " + FormatNumber("%.3g", 100 * m.p95) + " %) |";
      t += "\n";
    }
    return t;
  };
  return table("range", s.by_range) + "\n" + table("angle to the baseline", s.by_angle);
}

}  // namespace hovs::depth
