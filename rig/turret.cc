#include "rig/turret.h"

#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <cmath>

#include "calib/aruco_dictionary.h"
#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "core/yaml_reader.h"
#include "rig/focus.h"
#include "scenes/scene_config.h"

namespace hovs::rig {
namespace {

constexpr double kDeg = M_PI / 180.0;

AxisSpec ReadAxis(const YamlReader& r, const YAML::Node& n, const std::string& key, AxisId id) {
  const bool degrees = AxisIsAngular(id);
  r.OnlyKeys(n, key, {"min", "max", "step", "time_constant", "backlash", "noise"});
  for (const char* k : {"min", "max", "step", "time_constant"})
    HOVS_REQUIRE(n[k], r.Where(n, key), "missing '", key, ".", k, "'");
  const double s = degrees ? kDeg : 1.0;
  AxisSpec a;
  a.min = r.Number(n["min"], key + ".min") * s;
  a.max = r.Number(n["max"], key + ".max") * s;
  a.step = r.Positive(n["step"], key + ".step") * s;
  a.time_constant = r.Positive(n["time_constant"], key + ".time_constant");
  if (n["backlash"]) a.backlash = r.Number(n["backlash"], key + ".backlash") * s;
  if (n["noise"]) a.noise = r.Number(n["noise"], key + ".noise") * s;
  a.Check(r.Where(n, key), id);
  return a;
}

// The radius of mirror k's mounting plate about its axis: the rim, and the label's markers with their margins.
double PlateRadius(const TurretSpec& s, const TurretMirror& m) {
  const double half_diagonal = std::sqrt(0.5) * (s.label.marker_length + 2 * s.label.margin);
  double r = m.mirror.RimRadius();
  for (const Vec2d& c : s.label.centres) r = std::max(r, c.norm() + half_diagonal);
  return r;
}

// The machine's geometry, checked once at load so that an impossible machine is refused naming its key, not
// blamed later on a covered label or a stuck axis: the label beside the rim and in view, the plates apart on the
// turret, every slot and plate height within its axis' travel, the focus bracket within the focus travel, and
// motor steps fine enough for the alignment's tolerances.
void CheckMachineGeometry(const TurretSpec& s, const YamlReader& r, const YAML::Node& root) {
  const double half_diagonal = std::sqrt(0.5) * (s.label.marker_length + 2 * s.label.margin);
  const YAML::Node centres = root["label"]["centres"];
  for (size_t i = 0; i < s.label.centres.size(); ++i) {
    const std::string key = "label.centres[" + std::to_string(i) + "]";
    const Vec2d c = s.label.centres[i];
    for (size_t j = 0; j < i; ++j)
      HOVS_REQUIRE((c - s.label.centres[j]).lpNorm<Eigen::Infinity>() >= s.label.marker_length + 2 * s.label.margin,
                   r.Where(centres[i], key), "marker ", i, " overlaps marker ", j);
    for (const TurretMirror& m : s.mirrors) {
      // Seen by the camera directly: beside the mirror's rim, and inside the image at the plate's height.
      HOVS_REQUIRE(c.norm() - half_diagonal > m.mirror.RimRadius(), r.Where(centres[i], key), "marker ", i, " at ",
                   FormatNumber("%.4g", 1e3 * c.norm()), " mm from the axis lies under mirror '", m.id,
                   "' (rim radius ", FormatNumber("%.4g", 1e3 * m.mirror.RimRadius()),
                   " mm): the camera cannot see it");
      const double z = m.PlateHeight() - s.label.depth;
      for (int k = 0; k < 4; ++k) {
        const Vec3d p = Vec3d(c.x(), c.y(), z) + Vec3d(s.label.Corner(static_cast<int>(i), k).x() - c.x(),
                                                       s.label.Corner(static_cast<int>(i), k).y() - c.y(), 0);
        const double u = s.camera.cx + s.camera.fx * p.x() / p.z(), v = s.camera.cy + s.camera.fy * p.y() / p.z();
        HOVS_REQUIRE(u >= 0 && v >= 0 && u <= s.camera.width - 1 && v <= s.camera.height - 1, r.Where(centres[i], key),
                     "marker ", i, " at (", FormatNumber("%.4g", 1e3 * c.x()), ", ", FormatNumber("%.4g", 1e3 * c.y()),
                     ") mm lies outside the image under mirror '", m.id, "' (plate ", FormatNumber("%.4g", 1e3 * z),
                     " mm above the lens)");
      }
    }
  }
  const AxisSpec& turret = s.axes[static_cast<int>(AxisId::kTurret)];
  const YAML::Node mirrors = root["mirrors"];
  for (size_t i = 0; i < s.mirrors.size(); ++i) {
    const TurretMirror& m = s.mirrors[i];
    const std::string key = "mirrors[" + std::to_string(i) + "].slot_deg";
    HOVS_REQUIRE(m.slot >= turret.min && m.slot <= turret.max, r.Where(mirrors[i], key), "mirror '", m.id, "' sits at ",
                 AxisValueText(AxisId::kTurret, m.slot), ", outside the turret's travel [",
                 AxisValueText(AxisId::kTurret, turret.min), ", ", AxisValueText(AxisId::kTurret, turret.max), "]");
    for (size_t j = 0; j < i; ++j) {
      const TurretMirror& o = s.mirrors[j];
      const double apart = 2 * s.turret_radius * std::abs(std::sin(0.5 * (m.slot - o.slot)));
      const double needed = PlateRadius(s, m) + PlateRadius(s, o);
      HOVS_REQUIRE(apart >= needed, r.Where(mirrors[i], key), "the plates of mirrors '", o.id, "' and '", m.id,
                   "' overlap: their axes are ", FormatNumber("%.4g", 1e3 * apart), " mm apart on the turret (radius ",
                   FormatNumber("%.4g", 1e3 * s.turret_radius), " mm), the plates need ",
                   FormatNumber("%.4g", 1e3 * needed), " mm");
    }
  }
  const AxisSpec& focus = s.axes[static_cast<int>(AxisId::kFocus)];
  const FocusOptions fo;
  for (const TurretMirror& m : s.mirrors) {
    // The label (at the plate) is focused for the alignment, the mirror image (within the focus bracket) after it.
    const double lo = std::min(m.PlateHeight(), fo.low * m.PlateHeight()), hi = fo.high * m.PlateHeight();
    HOVS_REQUIRE(focus.min <= m.PlateHeight() && focus.max >= m.PlateHeight() && focus.max > lo && focus.min < hi,
                 r.Where(root["axes"]["focus"], "axes.focus"), "the focus travel [", FormatNumber("%.4g", focus.min),
                 ", ", FormatNumber("%.4g", focus.max), "] m must hold mirror '", m.id, "''s plate at ",
                 FormatNumber("%.4g", m.PlateHeight()), " m and reach into its focus bracket ",
                 FormatNumber("%.4g", lo), " .. ", FormatNumber("%.4g", hi), " m");
  }
  // The loop positions to its tolerances (positioning.h AlignOptions); a coarser motor step cannot.
  const AlignOptions ao;
  const std::pair<AxisId, double> fine[] = {{AxisId::kX, ao.lateral_tolerance},
                                            {AxisId::kY, ao.lateral_tolerance},
                                            {AxisId::kRod, ao.height_tolerance},
                                            {AxisId::kTiltX, ao.tilt_tolerance},
                                            {AxisId::kTiltY, ao.tilt_tolerance}};
  for (const auto& [id, tol] : fine) {
    const AxisSpec& a = s.axes[static_cast<int>(id)];
    HOVS_REQUIRE(a.step <= 0.5 * tol, r.Where(root["axes"][AxisName(id)], std::string("axes.") + AxisName(id)),
                 "the step ", AxisValueText(id, a.step), " is coarser than half the alignment's tolerance (",
                 AxisValueText(id, tol), "): the loop could not settle within it");
  }
}

Eigen::Quaterniond Rotation(const Vec3d& v) { return QuaternionFromAngleAxis<double>(v); }

Vec3d RotationVector(const Eigen::Quaterniond& q) {
  const Eigen::AngleAxisd aa(q.normalized());
  return aa.angle() * aa.axis();
}

TurretSpec ParseUnguarded(const std::string& text, const std::string& source, const std::filesystem::path& base) {
  const YamlReader r(source);
  const YAML::Node root = r.Load(text);
  HOVS_REQUIRE(root.IsMap(), source, "expected a YAML mapping at the top level");
  r.OnlyKeys(root, "", {"name", "camera", "lens", "surroundings", "turret", "mirrors", "label", "axes", "render"});
  TurretSpec s;
  s.source = source, s.text = text;
  s.name = root["name"] ? r.Name(root["name"], "name") : "turret";
  YAML::Node n;
  {
    const YAML::Node& c = r.Require(root, "", "camera", &n);
    r.OnlyKeys(c, "camera", {"focal_length", "pixel_pitch", "width", "height", "lens_aperture"});
    YAML::Node v;
    const double f = r.Positive(r.Require(c, "camera", "focal_length", &v), "camera.focal_length");
    const double pitch = r.Positive(r.Require(c, "camera", "pixel_pitch", &v), "camera.pixel_pitch");
    const int w = r.Integer(r.Require(c, "camera", "width", &v), "camera.width");
    const int h = r.Integer(r.Require(c, "camera", "height", &v), "camera.height");
    HOVS_REQUIRE(w >= 64 && h >= 64 && w <= 20000 && h <= 20000, r.Where(c, "camera"), "size must be 64..20000 px");
    s.camera = PinholeCamera<double>::FromPhysical(f, pitch, w, h);
    s.pixel_pitch = pitch;
    s.lens_aperture = r.Positive(r.Require(c, "camera", "lens_aperture", &v), "camera.lens_aperture");
  }
  if (root["lens"]) {
    // The lens definition of design configs and scenes (core/lens.h); the focus axis sets its focus.
    const YAML::Node& l = root["lens"];
    HOVS_REQUIRE(!l.IsMap() || !l["focus_distance"], r.Where(l, "lens.focus_distance"),
                 "the focus axis sets the focus (axes.focus); the lens gives f_number or aperture_diameter");
    s.lens = r.Lens(l, "lens", s.camera.fx * s.pixel_pitch);
    HOVS_REQUIRE(s.lens->ApertureDiameter() <= s.lens_aperture, r.Where(l, "lens"), "its aperture (",
                 s.lens->ApertureDiameter() * 1e3, " mm at f/", s.lens->f_number,
                 ") is wider than the lens face, camera.lens_aperture ", s.lens_aperture * 1e3, " mm");
  }
  {
    const std::string file = r.String(r.Require(root, "", "surroundings", &n), "surroundings");
    auto cfg = std::make_shared<scenes::SceneConfig>(scenes::LoadSceneConfig(base / file));
    HOVS_REQUIRE(!cfg->description.units.empty(), r.Where(n, "surroundings"), "the scene ", file,
                 " has no unit to take the viewpoint's pose from");
    s.surroundings = cfg;
  }
  if (root["turret"]) {
    r.OnlyKeys(root["turret"], "turret", {"radius"});
    if (root["turret"]["radius"]) s.turret_radius = r.Positive(root["turret"]["radius"], "turret.radius");
  }
  {
    const YAML::Node& m = r.Require(root, "", "mirrors", &n);
    HOVS_REQUIRE(m.IsSequence() && m.size() >= 1 && m.size() <= 16, r.Where(m, "mirrors"),
                 "expected a list of 1 to 16 mirrors");
    for (size_t i = 0; i < m.size(); ++i) {
      const std::string k = "mirrors[" + std::to_string(i) + "]";
      r.OnlyKeys(m[i], k, {"id", "a", "b", "rim_diameter", "slot_deg"});
      YAML::Node v;
      TurretMirror t;
      t.id = r.Name(r.Require(m[i], k, "id", &v), k + ".id");
      for (const auto& o : s.mirrors)
        HOVS_REQUIRE(o.id != t.id, r.Where(m[i], k), "mirror id '", t.id, "' given twice");
      t.mirror = {r.Positive(r.Require(m[i], k, "a", &v), k + ".a"), r.Positive(r.Require(m[i], k, "b", &v), k + ".b"),
                  r.Positive(r.Require(m[i], k, "rim_diameter", &v), k + ".rim_diameter")};
      t.mirror.Check(r.Where(m[i], k));
      t.slot = r.Number(r.Require(m[i], k, "slot_deg", &v), k + ".slot_deg") * kDeg;
      s.mirrors.push_back(t);
    }
  }
  {
    const YAML::Node& l = r.Require(root, "", "label", &n);
    r.OnlyKeys(l, "label", {"dictionary", "marker_length", "margin", "centres"});
    if (l["dictionary"]) s.label.dictionary = r.String(l["dictionary"], "label.dictionary");
    calib::ArucoDictionaryId(s.label.dictionary, r.Where(l, "label.dictionary"));
    if (l["marker_length"]) s.label.marker_length = r.Positive(l["marker_length"], "label.marker_length");
    if (l["margin"]) s.label.margin = r.Positive(l["margin"], "label.margin");
    YAML::Node c;
    r.Require(l, "label", "centres", &c);
    HOVS_REQUIRE(c.IsSequence() && c.size() >= 3 && c.size() <= 16, r.Where(c, "label.centres"),
                 "expected 3 to 16 marker centres [x, y]");
    for (size_t i = 0; i < c.size(); ++i) {
      const std::string k = "label.centres[" + std::to_string(i) + "]";
      HOVS_REQUIRE(c[i].IsSequence() && c[i].size() == 2, r.Where(c[i], k), "expected [x, y]");
      s.label.centres.emplace_back(r.Number(c[i][0], k + "[0]"), r.Number(c[i][1], k + "[1]"));
    }
  }
  {
    const YAML::Node& a = r.Require(root, "", "axes", &n);
    r.OnlyKeys(a, "axes", {"turret", "rod", "x", "y", "tilt_x", "tilt_y", "focus"});
    for (int i = 0; i < kAxisCount; ++i) {
      YAML::Node v;
      const std::string k = std::string("axes.") + AxisName(AxisAt(i));
      s.axes[i] = ReadAxis(r, r.Require(a, "axes", AxisName(AxisAt(i)), &v), k, AxisAt(i));
    }
    const AxisSpec& rod = s.axes[static_cast<int>(AxisId::kRod)];
    for (const auto& m : s.mirrors)
      HOVS_REQUIRE(m.PlateHeight() >= rod.min && m.PlateHeight() <= rod.max, r.Where(a["rod"], "axes.rod"), "mirror '",
                   m.id, "' needs the plate at ", AxisValueText(AxisId::kRod, m.PlateHeight()),
                   ", outside the rod's travel [", AxisValueText(AxisId::kRod, rod.min), ", ",
                   AxisValueText(AxisId::kRod, rod.max), "]");
  }
  if (root["render"]) {
    const YAML::Node& o = root["render"];
    r.OnlyKeys(o, "render", {"downscale", "samples", "board_samples", "seed"});
    if (o["board_samples"]) s.board_samples = r.Integer(o["board_samples"], "render.board_samples");
    HOVS_REQUIRE(s.board_samples >= 1 && s.board_samples <= 1024, r.Where(o, "render.board_samples"),
                 "must be 1..1024");
    if (o["downscale"]) s.downscale = r.Integer(o["downscale"], "render.downscale");
    if (o["samples"]) s.samples = r.Integer(o["samples"], "render.samples");
    if (o["seed"]) s.seed = r.Seed(o["seed"], "render.seed");
    HOVS_REQUIRE(s.downscale >= 1 && s.downscale <= 16 && s.camera.width % s.downscale == 0 &&
                     s.camera.height % s.downscale == 0,
                 r.Where(o, "render.downscale"), "must be 1..16 and divide the image size");
    HOVS_REQUIRE(s.samples >= 1 && s.samples <= 1024, r.Where(o, "render.samples"), "must be 1..1024");
  }
  CheckMachineGeometry(s, r, root);
  s.world_from_cam = s.surroundings->description.units[0].world_from_mirror * CamFromMirror(s, 0, {}).Inverse();
  return s;
}

}  // namespace

Vec3d LabelSpec::Corner(int marker, int k) const {
  const double h = 0.5 * marker_length;
  static const double kSign[4][2] = {{-1, 1}, {1, 1}, {1, -1}, {-1, -1}};
  // The printed face looks at the camera (-z): its x is the plate's x, its up (+y as printed) the plate's -y.
  const Vec2d c = centres.at(marker);
  return Vec3d(c.x() + kSign[k][0] * h, c.y() - kSign[k][1] * h, -depth);
}

PinholeCamera<double> TurretSpec::ImageCamera() const {
  PinholeCamera<double> c = camera;
  c.fx /= downscale, c.fy /= downscale;
  c.width /= downscale, c.height /= downscale;
  // Pixel centres at (0, 0): the principal point scales about the top-left pixel's outer corner.
  c.cx = (camera.cx + 0.5) / downscale - 0.5;
  c.cy = (camera.cy + 0.5) / downscale - 0.5;
  return c;
}

int TurretSpec::MirrorIndex(const std::string& id) const {
  std::string known;
  for (size_t i = 0; i < mirrors.size(); ++i) {
    if (mirrors[i].id == id) return static_cast<int>(i);
    known += (known.empty() ? "" : ", ") + mirrors[i].id;
  }
  throw Error(source, "no mirror '" + id + "' (known: " + known + ")");
}

std::array<double, kAxisCount> TurretSpec::NominalAxes(int k, double focus) const {
  std::array<double, kAxisCount> a{};
  a[static_cast<int>(AxisId::kTurret)] = mirrors.at(k).slot;
  a[static_cast<int>(AxisId::kRod)] = mirrors.at(k).PlateHeight();
  a[static_cast<int>(AxisId::kFocus)] = focus;
  return a;
}

nlohmann::json MachineGeometryJson(const TurretSpec& s) {
  nlohmann::json mirrors = nlohmann::json::array();
  for (const auto& m : s.mirrors)
    mirrors.push_back({{"id", m.id},
                       {"a", m.mirror.a},
                       {"b", m.mirror.b},
                       {"rim_diameter", m.mirror.rim_diameter},
                       {"slot_rad", m.slot}});
  nlohmann::json centres = nlohmann::json::array();
  for (const auto& c : s.label.centres) centres.push_back({c.x(), c.y()});
  return {{"camera",
           {{"fx", s.camera.fx},
            {"fy", s.camera.fy},
            {"cx", s.camera.cx},
            {"cy", s.camera.cy},
            {"width", s.camera.width},
            {"height", s.camera.height}}},
          {"lens_aperture", s.lens_aperture},
          {"turret_radius", s.turret_radius},
          {"mirrors", mirrors},
          {"label",
           {{"dictionary", s.label.dictionary},
            {"marker_length", s.label.marker_length},
            {"margin", s.label.margin},
            {"centres", centres}}}};
}

TurretSpec ParseTurretSpec(const std::string& text, const std::string& source, const std::filesystem::path& base) {
  return WithYamlErrors(source, [&] { return ParseUnguarded(text, source, base); });
}

TurretSpec LoadTurretSpec(const std::filesystem::path& path) {
  RequireFile(path, "machine file");
  return ParseTurretSpec(ReadFile(path), path.string(), path.parent_path());
}

double MirrorPose::TiltRad() const {
  const Vec3d axis = Rotation(rotation) * Vec3d::UnitZ();
  return std::atan2(axis.head<2>().norm(), axis.z());
}

MirrorPose PoseFromAxes(const TurretSpec& spec, int k, const std::array<double, kAxisCount>& a,
                        const MirrorPose& seat) {
  const auto at = [&](AxisId id) { return a[static_cast<int>(id)]; };
  const double phi = at(AxisId::kTurret) - spec.mirrors.at(k).slot;
  const double R = spec.turret_radius;
  MirrorPose p;
  p.offset = Vec3d(R * (std::cos(phi) - 1) + at(AxisId::kX), R * std::sin(phi) + at(AxisId::kY),
                   at(AxisId::kRod) - spec.mirrors[k].PlateHeight()) +
             seat.offset;
  const Eigen::Quaterniond q = Rotation(Vec3d(0, 0, phi)) * Rotation(Vec3d(at(AxisId::kTiltX), 0, 0)) *
                               Rotation(Vec3d(0, at(AxisId::kTiltY), 0)) * Rotation(seat.rotation);
  p.rotation = RotationVector(q);
  return p;
}

Rigid3d CamFromMirror(const TurretSpec& spec, int k, const MirrorPose& pose) {
  const HyperboloidMirror<double>& m = spec.mirrors.at(k).mirror;
  const Vec3d c(0, 0, m.RimZ());
  const Eigen::Quaterniond q = Rotation(pose.rotation);
  const Rigid3d nominal_from_mirror(q, c + pose.offset - q * c);
  return Rigid3d::Translation(Vec3d(0, 0, 2 * m.c())) * nominal_from_mirror;
}

MirrorPose PoseFromCamFromMirror(const TurretSpec& spec, int k, const Rigid3d& cam_from_mirror) {
  const HyperboloidMirror<double>& m = spec.mirrors.at(k).mirror;
  const Vec3d c(0, 0, m.RimZ());
  const Rigid3d nominal_from_mirror = Rigid3d::Translation(Vec3d(0, 0, -2 * m.c())) * cam_from_mirror;
  MirrorPose p;
  p.rotation = RotationVector(nominal_from_mirror.rotation);
  p.offset = nominal_from_mirror.translation - c + nominal_from_mirror.rotation * c;
  return p;
}

CatadioptricCamera<double> RigAt(const TurretSpec& spec, int k, const MirrorPose& pose) {
  CatadioptricCamera<double> rig =
      CatadioptricCamera<double>::Aligned(spec.mirrors.at(k).mirror, spec.camera, 0.5 * spec.lens_aperture);
  rig.cam_from_mirror = CamFromMirror(spec, k, pose);
  return rig;
}

scenes::SceneConfig TurretSceneConfig(const TurretSpec& spec, int k, const MirrorPose& pose, double focus_distance,
                                      uint64_t seed, bool label_covered) {
  scenes::SceneConfig cfg = *spec.surroundings;
  cfg.name = spec.name + "-" + spec.mirrors.at(k).id;
  raytrace::SceneDescription& desc = cfg.description;
  desc.units.clear();
  raytrace::CatadioptricUnit unit;
  unit.name = spec.mirrors.at(k).id;
  unit.rig = RigAt(spec, k, pose);
  unit.rig.camera = spec.ImageCamera();
  unit.world_from_mirror = spec.world_from_cam * unit.rig.cam_from_mirror;
  desc.units.push_back(unit);

  // The label: one textured rectangle per marker, on the plate's underside, facing the camera.
  int next_id = raytrace::kFirstObjectId;
  for (const auto& o : desc.objects) next_id = std::max(next_id, o.id + 1);
  desc.objects.push_back({next_id, "label", "label"});
  const cv::Ptr<cv::aruco::Dictionary> dict =
      cv::aruco::getPredefinedDictionary(calib::ArucoDictionaryId(spec.label.dictionary, spec.source));
  const HyperboloidMirror<double>& m = spec.mirrors[k].mirror;
  const double side = spec.label.marker_length + 2 * spec.label.margin;
  const int px_per_cell = 40, cells = dict->markerSize + 2;
  const int marker_px = cells * px_per_cell;
  const int margin_px = static_cast<int>(std::lround(spec.label.margin / spec.label.marker_length * marker_px));
  for (size_t i = 0; i < spec.label.centres.size(); ++i) {
    cv::Mat marker, img(marker_px + 2 * margin_px, marker_px + 2 * margin_px, CV_8UC1, cv::Scalar(255));
    cv::aruco::drawMarker(dict, static_cast<int>(i), marker_px, marker, 1);
    if (!label_covered) marker.copyTo(img(cv::Rect(margin_px, margin_px, marker_px, marker_px)));
    auto tex = std::make_shared<raytrace::ImageTexture>(
        raytrace::ImageTexture::FromGray8(img.data, img.cols, img.rows, "label marker " + std::to_string(i)));
    for (float& p : tex->pixels) p = label_covered ? 0.5f : 0.05f + 0.9f * p;
    raytrace::Rect rect;
    rect.object_id = next_id;
    rect.width = rect.height = side;
    rect.front.kind = raytrace::Texture::Kind::kImage;
    rect.front.image = tex;
    rect.front.image_width = rect.front.image_height = side;
    // Rect frame: x along the plate's x, z towards the camera (-z of the mirror frame).
    const Vec2d c = spec.label.centres[i];
    const Rigid3d mirror_from_rect(Rotation(Vec3d(M_PI, 0, 0)), Vec3d(c.x(), c.y(), m.RimZ() - spec.label.depth));
    rect.world_from_rect = unit.world_from_mirror * mirror_from_rect;
    desc.rects.push_back(rect);
  }
  cfg.render.samples = spec.samples;
  cfg.render.seed = seed;
  cfg.render.lens_radius = spec.LensRadius();
  cfg.render.focus_distance = focus_distance;
  return cfg;
}

TurretImage RenderTurret(const TurretSpec& spec, int k, const MirrorPose& pose, double focus_distance, uint64_t seed,
                         bool label_covered) {
  const auto start = std::chrono::steady_clock::now();
  scenes::SceneConfig cfg = TurretSceneConfig(spec, k, pose, focus_distance, seed, label_covered);
  raytrace::SceneDescription desc = std::move(cfg.description);
  const raytrace::RayScene scene(std::move(desc));
  raytrace::RenderOptions ro = cfg.render;
  ro.ground_truth = false;
  ro.progress = false;
  const raytrace::Frame frame = raytrace::Render(scene, raytrace::ViewCamera::Unit(0), ro);
  int channels = 0;
  const raytrace::PixelBuffer img = raytrace::ApplySensor(frame, ro.sensor, seed, &channels);
  TurretImage out;
  out.width = frame.width, out.height = frame.height;
  out.grey.resize(static_cast<size_t>(out.width) * out.height);
  for (size_t p = 0; p < out.grey.size(); ++p) {
    double s = 0;
    for (int c = 0; c < channels; ++c) s += img[p * channels + c];
    out.grey[p] = static_cast<uint8_t>(std::clamp(std::lround(255.0 * s / channels), 0L, 255L));
  }
  out.render_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace hovs::rig
