#include "study/edge_check.h"

#include <chrono>
#include <cmath>
#include <sstream>

#include "core/format.h"
#include "core/io.h"

#include "optics/focus.h"
#include "optics/slanted_edge.h"
#include "raytrace/render.h"

namespace hovs::study {
namespace {

constexpr double kSlantDeg = 5.0;

// The image point of X (mirror frame = world frame here) on the aligned rig; false when it is not imaged.
bool Project(const CatadioptricCamera<double>& rig, const Vec3d& X, Vec2d* uv) {
  return rig.ImgFromMirror(X, uv) == ProjectionStatus::kOk;
}

// One edge of the target: render its region, measure its MTF, predict it from the exact spot.
EdgeResult MeasureEdge(const raytrace::RayScene& scene, const optics::OpticalSystem& sys, const EdgeCheckOptions& o,
                       const Vec3d& point, const Vec3d& along, const std::string& direction, double elevation,
                       double distance) {
  EdgeResult r;
  r.elevation_deg = elevation, r.distance = distance, r.direction = direction;
  Vec2d uv, uv2;
  if (!Project(sys.rig, point, &uv) || !Project(sys.rig, Vec3d(point + 1e-3 * distance * along), &uv2)) {
    r.note = "the edge is not imaged";
    return r;
  }
  const Vec2d d = uv2 - uv;
  const bool across_x = std::abs(d.y()) > std::abs(d.x());  // the edge runs along y: its spread is along x
  raytrace::RenderOptions ro;
  ro.samples = o.samples, ro.seed = o.seed, ro.ground_truth = false;
  ro.lens_radius = sys.lens.ApertureRadius(), ro.focus_distance = sys.lens.focus_distance;
  const int x0 = static_cast<int>(std::lround(uv.x())) - o.region / 2,
            y0 = static_cast<int>(std::lround(uv.y())) - o.region / 2;
  ro.region = {x0, y0, x0 + o.region, y0 + o.region};
  if (x0 < 0 || y0 < 0 || x0 + o.region > sys.rig.camera.width || y0 + o.region > sys.rig.camera.height) {
    r.note = "the edge's region leaves the image";
    return r;
  }
  const raytrace::Frame frame = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  std::vector<float> grey(size_t(o.region) * o.region);
  for (int y = 0; y < o.region; ++y)
    for (int x = 0; x < o.region; ++x) {
      const float* p = &frame.rgb[(size_t(y0 + y) * frame.width + (x0 + x)) * 3];
      grey[size_t(y) * o.region + x] = (p[0] + p[1] + p[2]) / 3;
    }
  const optics::EdgeMtf measured = optics::MeasureSlantedEdge(grey, o.region, o.region, across_x);
  if (!measured.ok) {
    r.note = "no edge found in the rendered region";
    return r;
  }
  r.measured_mtf50 = measured.mtf50;
  const optics::Bundle b = optics::TraceBundle(sys.rig, point, sys.lens.ApertureRadius(),
                                               optics::PupilPoints(sys.pupil_samples, sys.lens.ApertureRadius()));
  const optics::Spot spot = optics::SpotAt(b, sys.rig.camera, sys.lens.focus_distance, /*keep_points=*/true);
  if (!spot.Valid()) {
    r.note = "no ray of the edge point reaches the lens";
    return r;
  }
  r.predicted_rms = spot.rms;
  const Vec2d n = measured.normal;
  r.predicted_mtf50 = optics::Mtf50([&](double nu) {
    return optics::GeometricMtf(spot, n, nu) * optics::PixelMtf(nu * n.x()) * optics::PixelMtf(nu * n.y());
  });
  r.relative_error = std::abs(r.measured_mtf50 - r.predicted_mtf50) / r.predicted_mtf50;
  r.ok = r.relative_error <= o.tolerance;
  return r;
}

}  // namespace

void EdgeCheckOptions::Check(const std::string& where) const {
  camera.Check(where + ".camera");
  HOVS_REQUIRE(samples >= 16 && samples <= 65536, where, "samples must be in 16..65536 (got ", samples, ")");
  HOVS_REQUIRE(region >= 24 && region <= 512, where, "region must be in 24..512 px (got ", region, ")");
  HOVS_REQUIRE(!distances.empty(), where, "needs at least one distance");
  for (double d : distances)
    HOVS_REQUIRE(std::isfinite(d) && d > 0.2 && d <= 1000, where, "distances must be in (0.2, 1000] m");
  HOVS_REQUIRE(std::isfinite(tolerance) && tolerance > 0, where, "tolerance must be positive");
}

EdgeCheck RunEdgeCheck(const EdgeCheckOptions& o) {
  o.Check("edge check");
  const auto start = std::chrono::steady_clock::now();
  EdgeCheck out;
  out.options = o;
  design::DesignProblem problem;
  problem.camera = o.camera;
  const design::Metrics m = design::Evaluate(o.mirror, problem);
  std::vector<double> elevations = o.elevations_deg;
  if (elevations.empty())
    for (int i = 0; i < 5; ++i) elevations.push_back(m.lower_deg + (m.upper_deg - m.lower_deg) * (i + 0.5) / 5);
  for (const double e : elevations)
    HOVS_REQUIRE(e > m.lower_deg && e < m.upper_deg, "edge check (elevations)", "elevation ", e,
                 " deg is outside the design's field (", FormatNumber("%.2f", m.lower_deg), " .. ",
                 FormatNumber("%.2f", m.upper_deg), " deg)");
  design::CameraSpec camera = o.camera;
  if (std::isinf(camera.lens.focus_distance)) {
    // Focused at infinity: render at the best single focus over the field for 1 m .. infinity instead.
    optics::OpticalSystem coarse;
    coarse.rig = design::RigOf(o.mirror, camera);
    coarse.lens = camera.Lens();
    coarse.pixel_pitch = camera.pixel_pitch;
    coarse.pupil_samples = 64;
    const auto fields = optics::FieldGrid(m.lower_deg, m.upper_deg, 24, optics::DistanceGrid(1.0, 1e4, 6));
    camera.lens.focus_distance =
        optics::BestSingleFocus(coarse, optics::TraceFields(coarse, fields), 1.5 * camera.focal_length).focus_distance;
  }
  out.options.camera = camera;
  optics::OpticalSystem sys;
  sys.rig = design::RigOf(o.mirror, camera);
  sys.lens = camera.Lens();
  sys.pixel_pitch = camera.pixel_pitch;
  sys.pupil_samples = 1024;
  out.focus_distance = sys.lens.focus_distance;

  for (const double e : elevations)
    for (const double dist : o.distances) {
      const Vec3d X = optics::FieldPoint{e, 0, dist}.Position();
      const Vec3d z = -X.normalized();
      const Vec3d x0(0, 1, 0), y0 = z.cross(x0);
      const double s = kSlantDeg * M_PI / 180;
      const Vec3d xr = std::cos(s) * x0 + std::sin(s) * y0, yr = -std::sin(s) * x0 + std::cos(s) * y0;
      // Offsets along each edge that put its region clear of the corner: 0.75 region in the image.
      const auto offset = [&](const Vec3d& along) {
        Vec2d a, b;
        if (!Project(sys.rig, X, &a) || !Project(sys.rig, Vec3d(X + 1e-3 * dist * along), &b)) return 0.0;
        return 1e-3 * dist * 0.75 * o.region / std::max((b - a).norm(), 1e-9);
      };
      const double sa = offset(xr), sb = offset(yr);
      if (!(sa > 0) || !(sb > 0)) {
        for (const char* dir : {"radial", "tangential"})
          out.results.push_back({e, dist, dir, 0, 0, 0, 0, false, "the target is not imaged"});
        continue;
      }
      raytrace::SceneDescription desc;
      raytrace::CatadioptricUnit unit;
      unit.rig = sys.rig;
      desc.units.push_back(unit);
      raytrace::Rect target;
      Eigen::Matrix3d R;
      R.col(0) = xr, R.col(1) = yr, R.col(2) = z;
      target.world_from_rect = Rigid3d(Eigen::Quaterniond(R), X);
      const double half = std::min(2.5 * std::max(sa, sb), 0.8 * dist);
      target.width = target.height = 2 * half;
      target.front.kind = raytrace::Texture::Kind::kChecker;
      target.front.square = half, target.front.squares_x = 2, target.front.squares_y = 2;
      target.front.colour_a = {0.05f, 0.05f, 0.05f}, target.front.colour_b = {0.9f, 0.9f, 0.9f};
      desc.rects.push_back(target);
      desc.objects.push_back({raytrace::kFirstObjectId, "edge target", "plane"});
      const raytrace::RayScene scene(std::move(desc));
      // The edge along the azimuth (x) images tangentially: its spread is radial; the other, tangential.
      out.results.push_back(MeasureEdge(scene, sys, o, X + sa * xr, xr, "radial", e, dist));
      out.results.push_back(MeasureEdge(scene, sys, o, X + sb * yr, yr, "tangential", e, dist));
    }
  for (const EdgeResult& r : out.results) {
    out.passed += r.ok ? 1 : 0;
    if (r.predicted_mtf50 > 0) out.max_relative_error = std::max(out.max_relative_error, r.relative_error);
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

nlohmann::json EdgeCheckJson(const EdgeCheck& c) {
  nlohmann::json j;
  const EdgeCheckOptions& o = c.options;
  j["mirror"] = {{"a", o.mirror.a}, {"b", o.mirror.b}, {"d", o.mirror.d}};
  j["lens"] = {{"focal_length", o.camera.focal_length},
               {"f_number", o.camera.lens.f_number},
               {"focus_distance", c.focus_distance},
               {"sensor_distance", o.camera.Lens().SensorDistance()}};
  j["samples"] = o.samples, j["region_px"] = o.region, j["seed"] = o.seed, j["tolerance"] = o.tolerance;
  nlohmann::json rows = nlohmann::json::array();
  for (const EdgeResult& r : c.results)
    rows.push_back({{"elevation_deg", r.elevation_deg},
                    {"distance", r.distance},
                    {"direction", r.direction},
                    {"predicted_rms_px", r.predicted_rms},
                    {"predicted_mtf50", r.predicted_mtf50},
                    {"measured_mtf50", r.measured_mtf50},
                    {"relative_error", r.relative_error},
                    {"ok", r.ok},
                    {"note", r.note}});
  j["edges"] = rows;
  j["passed"] = c.passed, j["edges_total"] = c.results.size();
  j["max_relative_error"] = c.max_relative_error;
  j["seconds"] = c.seconds;
  return j;
}

std::string EdgeCheckSummary(const EdgeCheck& c) {
  std::ostringstream s;
  s << "hovs edge-check: " << c.passed << " of " << c.results.size() << " rendered edges within "
    << FormatNumber("%.0f", 100 * c.options.tolerance) << " % of the predicted MTF50 (worst "
    << FormatNumber("%.1f", 100 * c.max_relative_error) << " %); f/"
    << FormatNumber("%.3g", c.options.camera.lens.f_number) << " focused at " << FormatNumber("%.4f", c.focus_distance)
    << " m, " << c.options.samples << " samples per pixel\n";
  s << "  elevation  distance  direction   RMS (px)  MTF50 predicted  measured  error\n";
  for (const EdgeResult& r : c.results)
    s << "  " << FormatNumber("%9.2f", r.elevation_deg) << FormatNumber("%10.3g", r.distance) << "  " << r.direction
      << std::string(12 - r.direction.size(), ' ') << FormatNumber("%8.3f", r.predicted_rms)
      << FormatNumber("%17.4f", r.predicted_mtf50) << FormatNumber("%10.4f", r.measured_mtf50)
      << FormatNumber("%6.1f", 100 * r.relative_error) << " %" << (r.ok ? "" : "  NOT MET")
      << (r.note.empty() ? "" : "  " + r.note) << "\n";
  return s.str();
}

std::string WriteEdgeCheck(const EdgeCheck& c, const std::filesystem::path& out,
                           const std::map<std::string, std::string>& versions) {
  StagedDirectory stage(out, "edge-check", {});
  nlohmann::json j = EdgeCheckJson(c);
  j["versions"] = versions;
  WriteFileAtomic(stage.staging() / "edge_check.json", j.dump(2) + "\n");
  std::ostringstream csv;
  csv << "elevation_deg,distance_m,direction,predicted_rms_px,predicted_mtf50,measured_mtf50,relative_error,ok\n";
  for (const EdgeResult& r : c.results)
    csv << FormatNumber("%.6f", r.elevation_deg) << ',' << FormatNumber("%.6g", r.distance) << ',' << r.direction << ','
        << FormatNumber("%.5f", r.predicted_rms) << ',' << FormatNumber("%.5f", r.predicted_mtf50) << ','
        << FormatNumber("%.5f", r.measured_mtf50) << ',' << FormatNumber("%.5f", r.relative_error) << ','
        << (r.ok ? 1 : 0) << '\n';
  WriteFileAtomic(stage.staging() / "edges.csv", csv.str());
  const std::string summary = EdgeCheckSummary(c);
  WriteFileAtomic(stage.staging() / "summary.txt", summary);
  stage.Commit();
  return summary;
}

}  // namespace hovs::study
