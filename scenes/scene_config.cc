#include "scenes/scene_config.h"

#include <opencv2/aruco.hpp>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/core.hpp>

#include <cmath>
#include <map>
#include <memory>

#include "calib/aruco_dictionary.h"
#include "core/error.h"
#include "core/io.h"
#include "core/yaml_reader.h"

namespace hovs::scenes {

using raytrace::Rect;
using raytrace::Texture;

namespace {
constexpr double kDeg = M_PI / 180.0;

cv::Ptr<cv::aruco::GridBoard> MakeGridBoard(const BoardSpec& s) {
  return cv::aruco::GridBoard::create(
      s.markers_x, s.markers_y, static_cast<float>(s.marker_length), static_cast<float>(s.marker_separation),
      cv::aruco::getPredefinedDictionary(calib::ArucoDictionaryId(s.dictionary, "board")));
}
}  // namespace

calib::CharucoSpec BoardSpec::Charuco() const {
  calib::CharucoSpec c;
  c.squares_x = squares_x, c.squares_y = squares_y, c.square = square, c.marker = marker_length;
  c.dictionary = dictionary;
  return c;
}

double BoardSpec::Width() const {
  return kind != Kind::kAruco ? squares_x * square + 2 * margin
                              : markers_x * marker_length + (markers_x - 1) * marker_separation + 2 * margin;
}
double BoardSpec::Height() const {
  return kind != Kind::kAruco ? squares_y * square + 2 * margin
                              : markers_y * marker_length + (markers_y - 1) * marker_separation + 2 * margin;
}

std::vector<std::pair<int, Vec2d>> BoardSpec::Corners() const {
  std::vector<std::pair<int, Vec2d>> out;
  if (kind == Kind::kChecker) {
    for (int j = 1; j < squares_y; ++j)
      for (int i = 1; i < squares_x; ++i)
        out.emplace_back((j - 1) * (squares_x - 1) + (i - 1),
                         Vec2d((i - 0.5 * squares_x) * square, (j - 0.5 * squares_y) * square));
    return out;
  }
  if (kind == Kind::kCharuco) {
    const calib::CharucoSpec c = Charuco();
    for (int id = 0; id < c.Cols() * c.Rows(); ++id) out.emplace_back(id, c.CornerXY(id));
    return out;
  }
  // OpenCV 4.6's GridBoard object points: origin at the pattern's top-left as printed, y down the print;
  // hovs' board frame has y up and z out of the print, so t = h / 2 - y.
  const auto board = MakeGridBoard(*this);
  const double w = Width() - 2 * margin, h = Height() - 2 * margin;
  for (size_t m = 0; m < board->objPoints.size(); ++m)
    for (int k = 0; k < 4; ++k) {
      const cv::Point3f& p = board->objPoints[m][k];
      out.emplace_back(4 * board->ids[m] + k, Vec2d(p.x - 0.5 * w, 0.5 * h - p.y));
    }
  return out;
}

void CheckBoard(const BoardSpec& s, const std::string& where) {
  HOVS_REQUIRE(s.margin >= 0 && std::isfinite(s.margin), where, "margin must be >= 0");
  if (s.kind == BoardSpec::Kind::kChecker) {
    HOVS_REQUIRE(s.squares_x >= 2 && s.squares_y >= 2, where, "a checkerboard needs at least 2 x 2 squares");
    HOVS_REQUIRE(s.squares_x <= 1000 && s.squares_y <= 1000, where,
                 "a checkerboard has at most 1000 x 1000 squares (got ", s.squares_x, " x ", s.squares_y, ")");
    HOVS_REQUIRE(s.square > 0 && std::isfinite(s.square), where, "square size must be positive");
  } else if (s.kind == BoardSpec::Kind::kCharuco) {
    s.Charuco().Check(where);
  } else {
    calib::ArucoDictionaryId(s.dictionary, where);
    HOVS_REQUIRE(s.markers_x >= 1 && s.markers_y >= 1, where, "needs at least one marker");
    HOVS_REQUIRE(s.marker_length > 0 && s.marker_separation >= 0, where, "marker sizes must be positive");
  }
}

Rect MakeBoardRect(const BoardSpec& s, const Rigid3d& world_from_board, int object_id) {
  Rect r;
  r.object_id = object_id;
  r.world_from_rect = world_from_board;
  r.width = s.Width(), r.height = s.Height();
  if (s.kind == BoardSpec::Kind::kChecker) {
    r.front.kind = Texture::Kind::kChecker;
    r.front.square = s.square;
    r.front.squares_x = s.squares_x, r.front.squares_y = s.squares_y;
    r.front.colour_a = {0.05f, 0.05f, 0.05f};
    r.front.colour_b = {0.95f, 0.95f, 0.95f};
    r.front.margin = {0.95f, 0.95f, 0.95f};
    return r;
  }
  // Draw the ArUco or ChArUco board at a resolution where every edge falls on a pixel edge (so the texture is
  // exact) and markers get at least 120 pixels.
  const bool charuco = s.kind == BoardSpec::Kind::kCharuco;
  double ppm = 0;
  for (double cand : {1000.0, 2000.0, 4000.0, 5000.0, 10000.0, 20000.0}) {
    const auto integral = [&](double v) { return std::abs(v * cand - std::round(v * cand)) < 1e-6; };
    const bool edges =
        charuco ? integral(s.square) && integral(0.5 * (s.square - s.marker_length)) : integral(s.marker_separation);
    if (integral(s.marker_length) && edges && integral(s.margin) && s.marker_length * cand >= 120 &&
        s.Width() * cand <= 16000 && s.Height() * cand <= 16000) {
      ppm = cand;
      break;
    }
  }
  HOVS_REQUIRE(ppm > 0, "aruco board",
               "marker length, separation and margin must be whole multiples of 0.05 mm "
               "and the board at most 16000 px at that resolution");
  const int w = static_cast<int>(std::lround(s.Width() * ppm)), h = static_cast<int>(std::lround(s.Height() * ppm));
  const int margin = static_cast<int>(std::lround(s.margin * ppm));
  cv::Mat img;
  if (charuco) {
    cv::aruco::CharucoBoard::create(s.squares_x, s.squares_y, static_cast<float>(s.square),
                                    static_cast<float>(s.marker_length),
                                    cv::aruco::getPredefinedDictionary(calib::ArucoDictionaryId(s.dictionary, "board")))
        ->draw(cv::Size(w, h), img, margin, 1);
  } else {
    MakeGridBoard(s)->draw(cv::Size(w, h), img, margin, 1);
  }
  auto tex = std::make_shared<raytrace::ImageTexture>(raytrace::ImageTexture::FromGray8(
      img.data, img.cols, img.rows, (charuco ? "charuco:" : "aruco:") + s.dictionary));
  // Paper white and ink black, like a print.
  for (float& p : tex->pixels) p = 0.05f + 0.9f * p;
  r.front.kind = Texture::Kind::kImage;
  r.front.image = tex;
  r.front.image_width = s.Width(), r.front.image_height = s.Height();
  r.front.margin = {0.95f, 0.95f, 0.95f};
  return r;
}

Rigid3d LookAt(const Vec3d& position, const Vec3d& target, double roll) {
  const Vec3d z = (target - position).normalized();
  Vec3d x = Vec3d(0, 0, 1).cross(z);
  if (x.norm() < 1e-9) x = Vec3d(1, 0, 0);
  x.normalize();
  const Vec3d y = z.cross(x);
  Mat3<double> R;
  R.col(0) = x, R.col(1) = y, R.col(2) = z;
  const Eigen::Quaterniond q = Eigen::Quaterniond(R) * Eigen::Quaterniond(Eigen::AngleAxisd(roll, Vec3d::UnitZ()));
  return Rigid3d(q.normalized(), position);
}

Rigid3d MisalignedCamFromMirror(const HyperboloidMirror<double>& mirror, const Vec3d& tilt, const Vec3d& offset,
                                double height_error) {
  return CamFromMirrorMisaligned<double>(mirror, tilt, Vec3d(offset + Vec3d(0, 0, -height_error)));
}

namespace {

Rigid3d ReadPose(const YamlReader& r, const YAML::Node& n, const std::string& key) {
  r.OnlyKeys(n, key, {"position", "rotation_deg", "look_at", "roll_deg"});
  YAML::Node pos;
  const Vec3d p = r.Vector3(r.Require(n, key, "position", &pos), key + ".position");
  const auto within = [&](const Vec3d& v, const YAML::Node& at, const std::string& k) {
    HOVS_REQUIRE(v.cwiseAbs().maxCoeff() <= raytrace::kWorldExtent, r.Where(at, k), "lies more than ",
                 raytrace::kWorldExtent,
                 " m from the world origin: the renderer traces in single precision (1 mm "
                 "there); give the scene in local coordinates");
  };
  within(p, pos, key + ".position");
  HOVS_REQUIRE(!(n["rotation_deg"] && n["look_at"]), r.Where(n, key), "give rotation_deg or look_at, not both");
  if (n["look_at"]) {
    const Vec3d t = r.Vector3(n["look_at"], key + ".look_at");
    within(t, n["look_at"], key + ".look_at");
    HOVS_REQUIRE((t - p).norm() > 1e-9, r.Where(n["look_at"], key + ".look_at"), "look_at equals position");
    return LookAt(p, t, n["roll_deg"] ? r.Number(n["roll_deg"], key + ".roll_deg") * kDeg : 0.0);
  }
  const Vec3d aa =
      n["rotation_deg"] ? Vec3d(r.Vector3(n["rotation_deg"], key + ".rotation_deg") * kDeg) : Vec3d::Zero();
  return Rigid3d(QuaternionFromAngleAxis<double>(aa), p);
}

Texture ReadTexture(const YamlReader& r, const YAML::Node& n, const std::string& key,
                    const std::filesystem::path& base) {
  r.OnlyKeys(n, key, {"solid", "checker", "noise", "image"});
  HOVS_REQUIRE(n.size() == 1, r.Where(n, key), "give exactly one of solid, checker, noise, image");
  Texture t;
  if (n["solid"]) {
    t.kind = Texture::Kind::kSolid;
    t.colour_a = r.Colour(n["solid"], key + ".solid");
  } else if (n["checker"]) {
    const YAML::Node c = n["checker"];
    const std::string k = key + ".checker";
    r.OnlyKeys(c, k, {"squares", "square", "dark", "light"});
    t.kind = Texture::Kind::kChecker;
    YAML::Node sq;
    r.Require(c, k, "squares", &sq);
    HOVS_REQUIRE(sq.IsSequence() && sq.size() == 2, r.Where(sq, k + ".squares"), "expected [nx, ny]");
    t.squares_x = r.Integer(sq[0], k + ".squares[0]"), t.squares_y = r.Integer(sq[1], k + ".squares[1]");
    HOVS_REQUIRE(t.squares_x >= 1 && t.squares_y >= 1, r.Where(sq, k + ".squares"),
                 "needs at least 1 x 1 squares (got ", t.squares_x, " x ", t.squares_y, ")");
    YAML::Node s;
    t.square = r.Positive(r.Require(c, k, "square", &s), k + ".square");
    if (c["dark"]) t.colour_a = r.Colour(c["dark"], k + ".dark");
    if (c["light"]) t.colour_b = t.margin = r.Colour(c["light"], k + ".light");
  } else if (n["noise"]) {
    const YAML::Node c = n["noise"];
    const std::string k = key + ".noise";
    r.OnlyKeys(c, k, {"scale", "octaves", "seed", "low", "high"});
    t.kind = Texture::Kind::kNoise;
    if (c["scale"]) t.scale = r.Positive(c["scale"], k + ".scale");
    if (c["octaves"]) t.octaves = r.Integer(c["octaves"], k + ".octaves");
    HOVS_REQUIRE(t.octaves >= 1 && t.octaves <= 12, r.Where(c, k + ".octaves"), "must be in 1..12");
    if (c["seed"]) {
      const uint64_t seed = r.Seed(c["seed"], k + ".seed");
      HOVS_REQUIRE(seed <= 0xFFFFFFFFu, r.Where(c["seed"], k + ".seed"), "a texture seed is at most 2^32 - 1");
      t.seed = static_cast<uint32_t>(seed);
    }
    if (c["low"]) t.colour_a = r.Colour(c["low"], k + ".low");
    if (c["high"]) t.colour_b = r.Colour(c["high"], k + ".high");
  } else {
    const YAML::Node c = n["image"];
    const std::string k = key + ".image";
    r.OnlyKeys(c, k, {"path", "width", "height"});
    YAML::Node p;
    std::filesystem::path file = r.String(r.Require(c, k, "path", &p), k + ".path");
    if (file.is_relative()) file = base / file;
    HOVS_REQUIRE(std::filesystem::is_regular_file(file), r.Where(p, k + ".path"),
                 "texture file not found: ", file.string());
    t.kind = Texture::Kind::kImage;
    t.image = std::make_shared<raytrace::ImageTexture>(raytrace::ImageTexture::Load(file.string()));
    YAML::Node w, h;
    t.image_width = r.Positive(r.Require(c, k, "width", &w), k + ".width");
    t.image_height = r.Positive(r.Require(c, k, "height", &h), k + ".height");
  }
  return t;
}

}  // namespace

namespace {
SceneConfig ParseSceneConfigUnguarded(const std::string& text, const std::string& source,
                                      const std::filesystem::path& base) {
  const YamlReader r(source);
  const YAML::Node root = r.Load(text);
  HOVS_REQUIRE(root.IsMap(), source, "expected a YAML mapping at the top level");
  r.OnlyKeys(root, "", {"name", "units", "objects", "sky", "render"});
  SceneConfig cfg;
  cfg.source = source, cfg.text = text;
  if (root["name"]) cfg.name = r.String(root["name"], "name");
  auto& desc = cfg.description;

  YAML::Node units;
  r.Require(root, "", "units", &units);
  HOVS_REQUIRE(units.IsSequence() && units.size() >= 1, r.Where(units, "units"), "expected a list of units");
  for (size_t i = 0; i < units.size(); ++i) {
    const YAML::Node u = units[i];
    const std::string k = "units[" + std::to_string(i) + "]";
    r.OnlyKeys(u, k,
               {"name", "mirror", "camera", "pose", "misalignment", "body_length", "velocity", "angular_velocity_deg"});
    raytrace::CatadioptricUnit unit;
    unit.name = u["name"] ? r.Name(u["name"], k + ".name") : "unit" + std::to_string(i);
    for (const auto& earlier : desc.units)
      HOVS_REQUIRE(earlier.name != unit.name, r.Where(u, k + ".name"), "a second unit named '", unit.name,
                   "' (unit names name the dataset's images)");
    YAML::Node m, c, pose;
    r.Require(u, k, "mirror", &m);
    r.OnlyKeys(m, k + ".mirror", {"a", "b", "rim_diameter", "mount_width"});
    YAML::Node a, b, d;
    HyperboloidMirror<double> mirror{
        r.Positive(r.Require(m, k + ".mirror", "a", &a), k + ".mirror.a"),
        r.Positive(r.Require(m, k + ".mirror", "b", &b), k + ".mirror.b"),
        r.Positive(r.Require(m, k + ".mirror", "rim_diameter", &d), k + ".mirror.rim_diameter")};
    r.Require(u, k, "camera", &c);
    const std::string kc = k + ".camera";
    r.OnlyKeys(
        c, kc,
        {"focal_length", "pixel_pitch", "width", "height", "lens_aperture", "lens", "distortion", "principal_point"});
    YAML::Node f, pp, w, h, la;
    const double focal = r.Positive(r.Require(c, kc, "focal_length", &f), kc + ".focal_length");
    const double pitch = r.Positive(r.Require(c, kc, "pixel_pitch", &pp), kc + ".pixel_pitch");
    HOVS_REQUIRE(pitch >= 1e-7 && pitch <= 1e-3, r.Where(pp, kc + ".pixel_pitch"),
                 "must be in 1e-7 .. 1e-3 m (0.1 um to 1 mm; got ", pitch, ")");
    const int width = r.Integer(r.Require(c, kc, "width", &w), kc + ".width");
    const int height = r.Integer(r.Require(c, kc, "height", &h), kc + ".height");
    HOVS_REQUIRE(width > 0 && height > 0 && width <= 20000 && height <= 20000, r.Where(c, kc),
                 "image size must be 1..20000");
    const double lens = r.Positive(r.Require(c, kc, "lens_aperture", &la), kc + ".lens_aperture");
    // The lens (core/lens.h): the image scale is its sensor distance at the focus in force, not f.
    std::optional<ThinLens> thin_lens;
    if (c["lens"]) {
      thin_lens = r.Lens(c["lens"], kc + ".lens", focal);
      HOVS_REQUIRE(thin_lens->ApertureDiameter() <= lens, r.Where(c["lens"], kc + ".lens"), "its aperture (",
                   thin_lens->ApertureDiameter() * 1e3, " mm at f/", thin_lens->f_number,
                   ") is wider than the lens face, lens_aperture ", lens * 1e3, " mm");
      HOVS_REQUIRE(thin_lens->ApertureRadius() <= raytrace::kMaxApertureRadius, r.Where(c["lens"], kc + ".lens"),
                   "aperture radius above ", raytrace::kMaxApertureRadius, " m");
    }
    PinholeCamera<double> cam = thin_lens ? thin_lens->Camera(pitch, width, height)
                                          : PinholeCamera<double>::FromPhysical(focal, pitch, width, height);
    if (c["principal_point"]) {
      const YAML::Node p = c["principal_point"];
      HOVS_REQUIRE(p.IsSequence() && p.size() == 2, r.Where(p, kc + ".principal_point"), "expected [cx, cy] in pixels");
      cam.cx = r.Number(p[0], kc + ".principal_point[0]"), cam.cy = r.Number(p[1], kc + ".principal_point[1]");
    }
    if (c["distortion"]) {
      const YAML::Node dd = c["distortion"];
      HOVS_REQUIRE(dd.IsSequence() && dd.size() == 4, r.Where(dd, kc + ".distortion"), "expected [k1, k2, p1, p2]");
      cam.distortion = {r.Number(dd[0], kc + ".distortion[0]"), r.Number(dd[1], kc + ".distortion[1]"),
                        r.Number(dd[2], kc + ".distortion[2]"), r.Number(dd[3], kc + ".distortion[3]")};
    }
    unit.rig = CatadioptricCamera<double>::Aligned(mirror, cam, 0.5 * lens);
    unit.lens = thin_lens;
    if (u["misalignment"]) {
      const YAML::Node mis = u["misalignment"];
      const std::string km = k + ".misalignment";
      r.OnlyKeys(mis, km, {"tilt_deg", "offset", "height_error"});
      const Vec3d tilt = mis["tilt_deg"] ? Vec3d(r.Vector3(mis["tilt_deg"], km + ".tilt_deg") * kDeg) : Vec3d::Zero();
      const Vec3d off = mis["offset"] ? r.Vector3(mis["offset"], km + ".offset") : Vec3d::Zero();
      const double he = mis["height_error"] ? r.Number(mis["height_error"], km + ".height_error") : 0.0;
      unit.rig.cam_from_mirror = MisalignedCamFromMirror(mirror, tilt, off, he);
    }
    // The mount ring's width beyond the rim (default 15 mm): it bounds the field above the horizon.
    if (m["mount_width"])
      unit.mount_outer_radius = mirror.RimRadius() + r.Positive(m["mount_width"], k + ".mirror.mount_width");
    unit.world_from_mirror = ReadPose(r, r.Require(u, k, "pose", &pose), k + ".pose");
    if (u["body_length"]) unit.body_length = r.Positive(u["body_length"], k + ".body_length");
    if (u["velocity"]) {
      unit.velocity = r.Vector3(u["velocity"], k + ".velocity");
      HOVS_REQUIRE(unit.velocity.norm() <= 1000, r.Where(u["velocity"], k + ".velocity"),
                   "a unit moves at most 1000 m/s");
    }
    if (u["angular_velocity_deg"])
      unit.angular_velocity = r.Vector3(u["angular_velocity_deg"], k + ".angular_velocity_deg") * kDeg;
    unit.rig.Check(r.Where(u, k));
    desc.units.push_back(unit);
  }

  int next_id = raytrace::kFirstObjectId;
  if (root["objects"]) {
    const YAML::Node objs = root["objects"];
    HOVS_REQUIRE(objs.IsSequence(), r.Where(objs, "objects"), "expected a list");
    for (size_t i = 0; i < objs.size(); ++i) {
      const YAML::Node o = objs[i];
      const std::string k = "objects[" + std::to_string(i) + "]";
      YAML::Node type_node;
      const std::string type = r.String(r.Require(o, k, "type", &type_node), k + ".type");
      const int id = next_id++;
      const std::string name = o["name"] ? r.String(o["name"], k + ".name") : type + std::to_string(i);
      desc.objects.push_back({id, name, type});
      YAML::Node pose;
      if (type == "ground") {
        r.OnlyKeys(o, k, {"type", "name", "height", "size", "texture"});
        Rect g;
        g.object_id = id;
        const double z = o["height"] ? r.Number(o["height"], k + ".height") : 0.0;
        g.width = g.height = o["size"] ? r.Positive(o["size"], k + ".size") : 200.0;
        g.world_from_rect = Rigid3d::Translation(Vec3d(0, 0, z));
        g.double_sided = true;
        YAML::Node t;
        g.front = ReadTexture(r, r.Require(o, k, "texture", &t), k + ".texture", base);
        desc.rects.push_back(g);
      } else if (type == "board") {
        r.OnlyKeys(o, k, {"type", "name", "pose", "checker", "aruco", "charuco", "margin"});
        BoardSpec spec;
        HOVS_REQUIRE((o["checker"] ? 1 : 0) + (o["aruco"] ? 1 : 0) + (o["charuco"] ? 1 : 0) == 1, r.Where(o, k),
                     "a board is one of checker, aruco and charuco");
        // A required [nx, ny] of whole numbers.
        const auto pair = [&](const YAML::Node& c, const std::string& path, const std::string& key, int* x, int* y) {
          YAML::Node n;
          r.Require(c, path, key, &n);
          HOVS_REQUIRE(n.IsSequence() && n.size() == 2, r.Where(n, path + "." + key), "expected [nx, ny]");
          *x = r.Integer(n[0], path + "." + key + "[0]"), *y = r.Integer(n[1], path + "." + key + "[1]");
        };
        if (o["charuco"]) {
          const YAML::Node c = o["charuco"];
          const std::string kc = k + ".charuco";
          r.OnlyKeys(c, kc, {"squares", "square", "marker_length", "dictionary"});
          spec.kind = BoardSpec::Kind::kCharuco;
          YAML::Node s, ml;
          pair(c, kc, "squares", &spec.squares_x, &spec.squares_y);
          spec.square = r.Positive(r.Require(c, kc, "square", &s), kc + ".square");
          spec.marker_length = r.Positive(r.Require(c, kc, "marker_length", &ml), kc + ".marker_length");
          spec.dictionary = "DICT_4X4_250";
          if (c["dictionary"]) spec.dictionary = r.String(c["dictionary"], kc + ".dictionary");
        } else if (o["checker"]) {
          const YAML::Node c = o["checker"];
          r.OnlyKeys(c, k + ".checker", {"squares", "square"});
          YAML::Node s;
          pair(c, k + ".checker", "squares", &spec.squares_x, &spec.squares_y);
          spec.square = r.Positive(r.Require(c, k + ".checker", "square", &s), k + ".checker.square");
        } else {
          const YAML::Node c = o["aruco"];
          const std::string ka = k + ".aruco";
          r.OnlyKeys(c, ka, {"markers", "marker_length", "separation", "dictionary"});
          spec.kind = BoardSpec::Kind::kAruco;
          YAML::Node ml, sp;
          pair(c, ka, "markers", &spec.markers_x, &spec.markers_y);
          spec.marker_length = r.Positive(r.Require(c, ka, "marker_length", &ml), ka + ".marker_length");
          spec.marker_separation = r.Positive(r.Require(c, ka, "separation", &sp), ka + ".separation");
          if (c["dictionary"]) spec.dictionary = r.String(c["dictionary"], ka + ".dictionary");
        }
        if (o["margin"]) spec.margin = r.Number(o["margin"], k + ".margin");
        CheckBoard(spec, r.Where(o, k));
        BoardInstance b;
        b.name = name, b.object_id = id, b.spec = spec;
        b.world_from_board = ReadPose(r, r.Require(o, k, "pose", &pose), k + ".pose");
        b.rect_index = static_cast<int>(desc.rects.size());
        desc.rects.push_back(MakeBoardRect(spec, b.world_from_board, id));
        cfg.boards.push_back(b);
      } else if (type == "plane") {
        r.OnlyKeys(o, k, {"type", "name", "pose", "size", "texture", "double_sided"});
        Rect p;
        p.object_id = id;
        p.world_from_rect = ReadPose(r, r.Require(o, k, "pose", &pose), k + ".pose");
        YAML::Node sz, t;
        r.Require(o, k, "size", &sz);
        HOVS_REQUIRE(sz.IsSequence() && sz.size() == 2, r.Where(sz, k + ".size"), "expected [width, height]");
        p.width = r.Positive(sz[0], k + ".size[0]"), p.height = r.Positive(sz[1], k + ".size[1]");
        p.front = ReadTexture(r, r.Require(o, k, "texture", &t), k + ".texture", base);
        p.double_sided = o["double_sided"] ? r.Bool(o["double_sided"], k + ".double_sided") : true;
        desc.rects.push_back(p);
      } else if (type == "box") {
        r.OnlyKeys(o, k, {"type", "name", "pose", "size", "texture"});
        const Rigid3d world_from_box = ReadPose(r, r.Require(o, k, "pose", &pose), k + ".pose");
        YAML::Node sz, t;
        const Vec3d s = r.Vector3(r.Require(o, k, "size", &sz), k + ".size");
        HOVS_REQUIRE(s.minCoeff() > 0, r.Where(sz, k + ".size"), "box sides must be positive");
        const Texture tex = ReadTexture(r, r.Require(o, k, "texture", &t), k + ".texture", base);
        // The box's pose is at the centre of its bottom face.
        for (const Rect& face : raytrace::MakeBox(world_from_box, s, tex, id)) desc.rects.push_back(face);
      } else {
        throw Error(r.Where(type_node, k + ".type"),
                    "unknown object type '" + type + "' (known: board, box, ground, plane)");
      }
    }
  }
  if (root["sky"]) {
    const YAML::Node s = root["sky"];
    r.OnlyKeys(s, "sky", {"zenith", "horizon", "nadir"});
    if (s["zenith"]) desc.sky.zenith = r.Colour(s["zenith"], "sky.zenith");
    if (s["horizon"]) desc.sky.horizon = r.Colour(s["horizon"], "sky.horizon");
    if (s["nadir"]) desc.sky.nadir = r.Colour(s["nadir"], "sky.nadir");
  }
  if (root["render"]) {
    const YAML::Node rn = root["render"];
    r.OnlyKeys(rn, "render",
               {"samples", "seed", "ground_truth", "truth_channels", "truth_compression", "sensor", "lens_radius",
                "focus_distance", "exposure_time"});
    for (const char* key : {"lens_radius", "focus_distance"})
      HOVS_REQUIRE(!rn[key], r.Where(rn[key], std::string("render.") + key),
                   "the lens is each unit's camera.lens {f_number, focus_distance} (one definition: its image scale "
                   "follows the focus)");
    if (rn["exposure_time"]) cfg.render.exposure_time = r.Number(rn["exposure_time"], "render.exposure_time");
    if (rn["samples"]) cfg.render.samples = r.Integer(rn["samples"], "render.samples");
    if (rn["seed"]) cfg.render.seed = r.Seed(rn["seed"], "render.seed");
    if (rn["ground_truth"]) cfg.render.ground_truth = r.Bool(rn["ground_truth"], "render.ground_truth");
    if (rn["truth_channels"])
      cfg.render.truth_file.groups =
          raytrace::TruthFileOptions::ParseGroups(r.String(rn["truth_channels"], "render.truth_channels"),
                                                  r.Where(rn["truth_channels"], "render.truth_channels"));
    if (rn["truth_compression"])
      cfg.render.truth_file.compression = r.String(rn["truth_compression"], "render.truth_compression");
    if (rn["sensor"]) {
      const YAML::Node s = rn["sensor"];
      r.OnlyKeys(s, "render.sensor", {"gain", "vignetting", "full_well", "read_noise", "bayer", "bit_depth"});
      auto& so = cfg.render.sensor;
      if (s["gain"]) so.gain = r.Number(s["gain"], "render.sensor.gain");
      if (s["vignetting"]) so.vignetting = r.Number(s["vignetting"], "render.sensor.vignetting");
      if (s["full_well"]) so.full_well = r.Number(s["full_well"], "render.sensor.full_well");
      if (s["read_noise"]) so.read_noise = r.Number(s["read_noise"], "render.sensor.read_noise");
      if (s["bayer"]) so.bayer = r.Bool(s["bayer"], "render.sensor.bayer");
      if (s["bit_depth"]) so.bit_depth = r.Integer(s["bit_depth"], "render.sensor.bit_depth");
    }
    cfg.render.Check(r.Where(rn, "render"));
  }
  CheckUnitsClearOfObjects(cfg.description, source);
  return cfg;
}
}  // namespace

SceneConfig ParseSceneConfig(const std::string& text, const std::string& source, const std::filesystem::path& base) {
  return WithYamlErrors(source, [&] { return ParseSceneConfigUnguarded(text, source, base); });
}

UnitClearance::UnitClearance(const raytrace::SceneDescription& description) : objects_(description.objects) {
  if (description.rects.empty()) return;
  raytrace::SceneDescription objects = description;
  objects.units.clear();
  scene_ = std::make_unique<raytrace::RayScene>(objects);
}

UnitClearance::~UnitClearance() = default;

void UnitClearance::Check(const raytrace::CatadioptricUnit& u, const std::string& where) const {
  if (!scene_) return;
  const auto name_of = [&](int id) {
    for (const auto& o : objects_)
      if (o.id == id) return o.name;
    return "id " + std::to_string(id);
  };
  const auto& m = u.rig.mirror;
  const double rim = m.RimRadius(), z = m.RimZ();
  const double mount = u.mount_outer_radius > 0 ? u.mount_outer_radius : rim + 0.015;
  const auto world = [&](const Vec3d& p) { return u.world_from_mirror * p; };
  const Vec3d C = world(u.rig.CameraCentre());
  // Inside a box (whose faces face outwards: seen from inside, the scene shows through them): the six axis
  // directions from the camera centre all meet that box.
  int inside = -1;
  for (int k = 0; k < 6 && inside != -2; ++k) {
    Vec3d d = Vec3d::Zero();
    d(k / 2) = k % 2 ? -1.0 : 1.0;
    const raytrace::Hit h = scene_->Trace(C, d);
    const bool box = h.hit && std::any_of(objects_.begin(), objects_.end(),
                                          [&](const auto& o) { return o.id == h.object_id && o.type == "box"; });
    inside = box && (inside == -1 || inside == h.object_id) ? h.object_id : -2;
  }
  HOVS_REQUIRE(inside < 0, where, "unit '", u.name, "' is inside box '", name_of(inside), "'");
  std::vector<std::pair<Vec3d, Vec3d>> segments = {
      {C, world(u.rig.CameraCentre() - u.body_length * u.rig.OpticalAxis())}};
  for (int k = 0; k < 8; ++k) {
    const double a = k * M_PI / 4, ca = std::cos(a), sa = std::sin(a);
    segments.push_back({C, world(Vec3d(rim * ca, rim * sa, z))});
    if (k < 4) {
      segments.push_back({world(Vec3d(rim * ca, rim * sa, z)), world(Vec3d(-rim * ca, -rim * sa, z))});
      segments.push_back({world(Vec3d(mount * ca, mount * sa, z)), world(Vec3d(-mount * ca, -mount * sa, z))});
    }
  }
  for (const auto& [a, b] : segments) {
    if (!scene_->Occluded(a, b, 0)) continue;
    const raytrace::Hit h = scene_->Trace(a, (b - a).normalized());
    throw Error(where, internal::Concat("object '", name_of(h.object_id), "' passes through unit '", u.name,
                                        "' (its mirror, mount or camera body) near (", h.point.x(), ", ", h.point.y(),
                                        ", ", h.point.z(), ") m"));
  }
}

void CheckUnitsClearOfObjects(const raytrace::SceneDescription& description, const std::string& where) {
  if (description.units.empty()) return;
  const UnitClearance clearance(description);
  for (const auto& u : description.units) clearance.Check(u, where);
}

SceneConfig LoadSceneConfig(const std::filesystem::path& path) {
  RequireFile(path, "scene file");
  return ParseSceneConfig(ReadFile(path), path.string(), path.parent_path());
}

void DownscaleCameras(SceneConfig* cfg, int factor) {
  HOVS_REQUIRE(factor >= 1 && factor <= 16, "--downscale", "factor must lie in [1, 16] (got ", factor, ")");
  if (factor == 1) return;
  for (auto& u : cfg->description.units) {
    auto& c = u.rig.camera;
    HOVS_REQUIRE(c.width % factor == 0 && c.height % factor == 0, "--downscale", "unit ", u.name, ": ", c.width, "x",
                 c.height, " is not divisible by ", factor);
    // Pixel centres: u' = (u + 0.5) / f - 0.5.
    c.width /= factor, c.height /= factor;
    c.fx /= factor, c.fy /= factor;
    c.cx = (c.cx + 0.5) / factor - 0.5, c.cy = (c.cy + 0.5) / factor - 0.5;
  }
}

void SelectUnit(SceneConfig* cfg, const std::string& name) {
  auto& units = cfg->description.units;
  const auto it = std::find_if(units.begin(), units.end(), [&](const auto& u) { return u.name == name; });
  std::string names;
  for (const auto& u : units) names += " " + u.name;
  HOVS_REQUIRE(it != units.end(), "--unit", "no unit '", name, "' in scene ", cfg->name, " (units:", names, ")");
  std::rotate(units.begin(), it, it + 1);
}

}  // namespace hovs::scenes
