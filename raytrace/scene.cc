#include "raytrace/scene.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "core/error.h"
#include "core/vector_clones.h"

namespace hovs::raytrace {

Rgb Sky::Eval(const Vec3d& d) const {
  const double z = std::clamp(d.z(), -1.0, 1.0);
  const auto mix = [](const Rgb& a, const Rgb& b, double t) {
    const float f = static_cast<float>(t);
    return Rgb{a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])};
  };
  return z >= 0 ? mix(horizon, zenith, std::sqrt(z)) : mix(horizon, nadir, std::sqrt(-z));
}

// Analytic shapes as Embree user geometry. Intersections run in double in the shape's own frame.
// Embree hands the callbacks rays in the frame of the scene the geometry is attached to: the world, or for the
// parts of a moving unit (attached to a scene instanced with the unit's motion) the unit's mirror frame.
struct RayScene::UserGeometry {
  enum class Kind { kMirror, kAnnulus } kind = Kind::kMirror;
  int object_id = kMirrorId;
  int unit = -1;
  Rigid3d world_from_local, local_from_world;   // at time 0
  // The callbacks' frame from the local one: world_from_local, or mirror_from_local for a moving unit's part.
  Rigid3d ray_from_local;
  HyperboloidMirror<double> mirror;  // kMirror: local frame = mirror frame
  double r_inner = 0, r_outer = 0;   // kAnnulus: disc in local z = 0
  Rgb colour = {0, 0, 0}, back_colour = {0, 0, 0};
  // The transforms as matrices (a quaternion rotation costs twice a matrix product): set by Prepare().
  Eigen::Matrix3d R_local_from_world, R_world_from_local;
  Vec3d t_local_from_world;
  Eigen::Matrix3d R_local_from_ray, R_ray_from_local;
  Vec3d t_local_from_ray;
  void Prepare(bool instanced) {
    R_local_from_world = local_from_world.rotation.toRotationMatrix();
    R_world_from_local = world_from_local.rotation.toRotationMatrix();
    t_local_from_world = local_from_world.translation;
    if (!instanced) {   // the callbacks' rays are world rays: the same matrices, to the bit
      ray_from_local = world_from_local;
      R_local_from_ray = R_local_from_world, R_ray_from_local = R_world_from_local;
      t_local_from_ray = t_local_from_world;
      return;
    }
    const Rigid3d local_from_ray = ray_from_local.Inverse();
    R_local_from_ray = local_from_ray.rotation.toRotationMatrix();
    R_ray_from_local = ray_from_local.rotation.toRotationMatrix();
    t_local_from_ray = local_from_ray.translation;
  }

  // Ray in world coordinates (the unit at time 0); t along the given (not necessarily unit) direction.
  bool Intersect(const Vec3d& o_w, const Vec3d& d_w, double tnear, double tfar, double* t, Vec3d* n_w) const {
    return IntersectLocal(R_local_from_world * o_w + t_local_from_world, R_local_from_world * d_w, tnear, tfar, t,
                          n_w, R_world_from_local);
  }
  // Ray in the callbacks' frame; the normal in that frame.
  bool IntersectInRayFrame(const Vec3d& o_r, const Vec3d& d_r, double tnear, double tfar, double* t,
                           Vec3d* n_r) const {
    return IntersectLocal(R_local_from_ray * o_r + t_local_from_ray, R_local_from_ray * d_r, tnear, tfar, t, n_r,
                          R_ray_from_local);
  }
  // Ray in the local frame; the normal rotated by R_out_from_local.
  bool IntersectLocal(const Vec3d& o, const Vec3d& d, double tnear, double tfar, double* t, Vec3d* n_out,
                      const Eigen::Matrix3d& R_out_from_local) const {
    if (kind == Kind::kMirror) {
      double tt = 0;
      if (!mirror.IntersectSheet(o, d, &tt, tnear) || !(tt < tfar)) return false;
      const Vec3d p = o + tt * d;
      if (!mirror.WithinRim(p)) return false;
      *t = tt;
      if (n_out) *n_out = R_out_from_local * mirror.Normal(p);
      return true;
    }
    if (d.z() == 0) return false;
    const double tt = -o.z() / d.z();
    if (!(tt > tnear && tt < tfar)) return false;
    const Vec3d p = o + tt * d;
    const double r2 = p.x() * p.x() + p.y() * p.y();
    if (r2 < r_inner * r_inner || r2 > r_outer * r_outer) return false;
    *t = tt;
    if (n_out) *n_out = R_out_from_local.col(2);
    return true;
  }

  // The shape's bounding box in the frame of frame_from_local (the callbacks' frame, or the world at time 0).
  void Bounds(const Rigid3d& frame_from_local, RTCBounds* b) const {
    Vec3d lo_l, hi_l;
    if (kind == Kind::kMirror) {
      const double R = mirror.RimRadius();
      lo_l = Vec3d(-R, -R, mirror.VertexZ());
      hi_l = Vec3d(R, R, mirror.RimZ());
    } else {
      lo_l = Vec3d(-r_outer, -r_outer, 0);
      hi_l = Vec3d(r_outer, r_outer, 0);
    }
    Vec3d lo = Vec3d::Constant(HUGE_VAL), hi = Vec3d::Constant(-HUGE_VAL);
    for (int k = 0; k < 8; ++k) {
      const Vec3d c((k & 1) ? hi_l.x() : lo_l.x(), (k & 2) ? hi_l.y() : lo_l.y(), (k & 4) ? hi_l.z() : lo_l.z());
      const Vec3d w = frame_from_local * c;
      lo = lo.cwiseMin(w), hi = hi.cwiseMax(w);
    }
    const double pad = 1e-6;
    b->lower_x = static_cast<float>(lo.x() - pad), b->lower_y = static_cast<float>(lo.y() - pad);
    b->lower_z = static_cast<float>(lo.z() - pad);
    b->upper_x = static_cast<float>(hi.x() + pad), b->upper_y = static_cast<float>(hi.y() + pad);
    b->upper_z = static_cast<float>(hi.z() + pad);
  }
};

namespace {

using UG = RayScene::UserGeometry;

// Embree masks: for units 0..9, unit u's mirror has bit 1 + 3u, its lens face bit 2 + 3u and its mount ring bit
// 3 + 3u; every other geometry (and those of units from 10 on) has bit 0. A ray leaving unit u's mirror clears
// the mirror's bit; a ray leaving unit u's camera straight (it missed the mirror within the rim, so it cannot
// meet it, and it starts on the lens face) clears both. Embree then does not even call those callbacks. Units
// from 10 on share bit 0 (LaneRay's id test stays).
constexpr int kMaskUnits = 10;
unsigned MirrorMaskBit(int unit) { return unit >= 0 && unit < kMaskUnits ? 1u << (1 + 3 * unit) : 1u; }
unsigned LensMaskBit(int unit) { return unit >= 0 && unit < kMaskUnits ? 1u << (2 + 3 * unit) : 1u; }
unsigned MountMaskBit(int unit) { return unit >= 0 && unit < kMaskUnits ? 1u << (3 + 3 * unit) : 1u; }
inline unsigned RayMask(int from_mirror, int from_camera = -1) {
  // Selects, not branches (this runs for every ray).
  const unsigned fm = static_cast<unsigned>(from_mirror), fc = static_cast<unsigned>(from_camera);
  const unsigned clear_m = fm < kMaskUnits ? 1u << (1 + 3 * fm) : 0u;
  const unsigned clear_c = fc < kMaskUnits ? 3u << (1 + 3 * fc) : 0u;   // the mirror's and the lens face's bits
  return ~(clear_m | clear_c);
}

void UserBounds(const RTCBoundsFunctionArguments* args) {
  const auto* g = static_cast<const UG*>(args->geometryUserPtr);
  g->Bounds(g->ray_from_local, args->bounds_o);
}

// Lane i of a ray packet in double, or false when the lane is inactive or the ray leaves this very mirror
// (a ray leaving a unit's convex mirror cannot meet it again: its id says where it started).
bool LaneRay(const UG* g, const int* valid, RTCRayN* ray, unsigned N, unsigned i, Vec3d* o, Vec3d* d) {
  if (!valid[i]) return false;
  if (g->kind == UG::Kind::kMirror && RTCRayN_id(ray, N, i) == static_cast<unsigned>(g->unit + 1)) return false;
  *o = Vec3d(RTCRayN_org_x(ray, N, i), RTCRayN_org_y(ray, N, i), RTCRayN_org_z(ray, N, i));
  *d = Vec3d(RTCRayN_dir_x(ray, N, i), RTCRayN_dir_y(ray, N, i), RTCRayN_dir_z(ray, N, i));
  return true;
}

void UserIntersect(const RTCIntersectFunctionNArguments* args) {
  const auto* g = static_cast<const UG*>(args->geometryUserPtr);
  const unsigned N = args->N;
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, N);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, N);
  for (unsigned i = 0; i < N; ++i) {
    Vec3d o, d, n;
    if (!LaneRay(g, args->valid, ray, N, i, &o, &d)) continue;
    double t = 0;
    if (!g->IntersectInRayFrame(o, d, RTCRayN_tnear(ray, N, i), RTCRayN_tfar(ray, N, i), &t, &n)) continue;
    RTCRayN_tfar(ray, N, i) = static_cast<float>(t);
    RTCHitN_Ng_x(hit, N, i) = static_cast<float>(n.x());
    RTCHitN_Ng_y(hit, N, i) = static_cast<float>(n.y());
    RTCHitN_Ng_z(hit, N, i) = static_cast<float>(n.z());
    RTCHitN_u(hit, N, i) = 0;
    RTCHitN_v(hit, N, i) = 0;
    RTCHitN_primID(hit, N, i) = args->primID;
    RTCHitN_geomID(hit, N, i) = args->geomID;
    RTCHitN_instID(hit, N, i, 0) = args->context->instID[0];
  }
}

void UserOccluded(const RTCOccludedFunctionNArguments* args) {
  const auto* g = static_cast<const UG*>(args->geometryUserPtr);
  const unsigned N = args->N;
  RTCRayN* ray = args->ray;
  for (unsigned i = 0; i < N; ++i) {
    Vec3d o, d;
    if (!LaneRay(g, args->valid, ray, N, i, &o, &d)) continue;
    double t = 0;
    if (g->IntersectInRayFrame(o, d, RTCRayN_tnear(ray, N, i), RTCRayN_tfar(ray, N, i), &t, nullptr))
      RTCRayN_tfar(ray, N, i) = -std::numeric_limits<float>::infinity();
  }
}

// Half the width of a unit's camera body (a square box behind the lens face, within the lens face's disc).
double BodyHalfWidth(const CatadioptricUnit& u) { return 0.7 * u.rig.occluder_radius; }

// Radius of the mount ring that hides everything the camera sees past the rim.
double DefaultMountRadius(const CatadioptricUnit& u) {
  const auto& cam = u.rig.camera;
  const double half_w = 0.5 * cam.width / cam.fx, half_h = 0.5 * cam.height / cam.fy;
  const double tan_diag = std::hypot(half_w, half_h);
  const double height = u.rig.mirror.RimZ() + 2 * u.rig.mirror.c();
  return std::max(u.rig.mirror.RimRadius() + 0.015, 1.1 * height * tan_diag + 0.01);
}

}  // namespace

std::vector<Rect> MakeBox(const Rigid3d& world_from_base, const Vec3d& s, const Texture& texture, int object_id,
                          bool double_sided) {
  const double pi = M_PI;
  struct Face {
    Vec3d centre, axis_angle;
    double w, h;
  };
  const Face faces[] = {{Vec3d(0, 0, s.z()), Vec3d(0, 0, 0), s.x(), s.y()},
                        {Vec3d(0, 0, 0), Vec3d(pi, 0, 0), s.x(), s.y()},
                        {Vec3d(s.x() / 2, 0, s.z() / 2), Vec3d(0, pi / 2, 0), s.z(), s.y()},
                        {Vec3d(-s.x() / 2, 0, s.z() / 2), Vec3d(0, -pi / 2, 0), s.z(), s.y()},
                        {Vec3d(0, s.y() / 2, s.z() / 2), Vec3d(-pi / 2, 0, 0), s.x(), s.z()},
                        {Vec3d(0, -s.y() / 2, s.z() / 2), Vec3d(pi / 2, 0, 0), s.x(), s.z()}};
  std::vector<Rect> out;
  for (const Face& f : faces) {
    Rect r;
    r.object_id = object_id;
    r.world_from_rect = world_from_base * Rigid3d(QuaternionFromAngleAxis<double>(f.axis_angle), f.centre);
    r.width = f.w, r.height = f.h;
    r.front = texture;
    r.double_sided = double_sided;
    out.push_back(r);
  }
  return out;
}

namespace {

// Every part of the scene within kWorldExtent of the origin along each axis, and finite.
void CheckWorldExtent(const SceneDescription& d) {
  const auto inside = [](const Vec3d& p) { return p.allFinite() && p.cwiseAbs().maxCoeff() <= kWorldExtent; };
  const auto name_of = [&](int id) {
    for (const SceneObjectInfo& o : d.objects)
      if (o.id == id) return "'" + o.name + "'";
    return "with id " + std::to_string(id);
  };
  for (const Rect& r : d.rects) {
    const double hw = 0.5 * r.width, hh = 0.5 * r.height;
    for (const Vec3d& corner : {Vec3d(-hw, -hh, 0), Vec3d(hw, -hh, 0), Vec3d(hw, hh, 0), Vec3d(-hw, hh, 0)})
      HOVS_REQUIRE(inside(r.world_from_rect * corner), "scene object " + name_of(r.object_id),
                   "reaches beyond ", kWorldExtent, " m from the world origin along an axis: the renderer traces in "
                   "single precision (1 mm there); give the scene in local coordinates");
  }
  for (const CatadioptricUnit& u : d.units) {
    const HyperboloidMirror<double>& m = u.rig.mirror;
    const Vec3d camera = (u.world_from_mirror * u.rig.cam_from_mirror.Inverse()).translation;
    const Vec3d rim[4] = {Vec3d(m.RimRadius(), 0, m.RimZ()), Vec3d(-m.RimRadius(), 0, m.RimZ()),
                          Vec3d(0, m.RimRadius(), m.RimZ()), Vec3d(0, -m.RimRadius(), m.RimZ())};
    bool ok = inside(u.world_from_mirror.translation) && inside(camera) && std::isfinite(u.mount_outer_radius) &&
              u.mount_outer_radius <= kWorldExtent && std::isfinite(u.body_length) && u.body_length <= kWorldExtent;
    for (const Vec3d& p : rim) ok = ok && inside(u.world_from_mirror * p);
    HOVS_REQUIRE(ok, "unit " + u.name, "its mirror or camera reaches beyond ", kWorldExtent,
                 " m from the world origin along an axis: the renderer traces in single precision (1 mm there)");
  }
}

}  // namespace

RayScene::RayScene(SceneDescription description) : desc_(std::move(description)) {
  // Before any Embree object exists: an error here leaves nothing to release.
  CheckWorldExtent(desc_);
  device_ = rtcNewDevice(nullptr);
  HOVS_REQUIRE(device_ != nullptr, "embree", "cannot create a device (error ", static_cast<int>(rtcGetDeviceError(nullptr)), ")");
  scene_ = rtcNewScene(device_);
  native16_ = rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
  // Robust (watertight) intersection: Embree's default test may miss a ray that runs exactly along an edge or a
  // quad's diagonal (a ray through a rectangle's centre does), which would put a hole in the ground truth. It
  // costs about 2.5 % of a frame.
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);

  // Units that move during an exposure: their parts (mirror, mount ring, lens face, camera body) are traced
  // through an Embree instance that follows the motion (AttachMovingUnit), the other units' in the world.
  std::vector<char> moving(desc_.units.size(), 0);
  for (size_t ui = 0; ui < desc_.units.size(); ++ui)
    moving[ui] = desc_.units[ui].Moves();

  // Camera bodies of the units become rectangles (a box behind the lens face, along the optical axis): the still
  // units' first, then the moving units' (which go into their instances, not into the world's quad mesh).
  std::vector<std::pair<size_t, size_t>> body_rects(desc_.units.size());  // by unit: [first, last) in desc_.rects
  size_t world_rects = 0;
  for (const char pass : {0, 1}) {
    for (size_t ui = 0; ui < desc_.units.size(); ++ui) {
      if (moving[ui] != pass) continue;
      body_rects[ui].first = desc_.rects.size();
      const CatadioptricUnit& u = desc_.units[ui];
      u.rig.Check("unit " + u.name);
      const Rigid3d world_from_cam = u.world_from_mirror * u.rig.cam_from_mirror.Inverse();
      const double half = BodyHalfWidth(u);
      Texture body;
      body.colour_a = u.body_colour;
      for (Rect r : MakeBox(world_from_cam * Rigid3d::Translation(Vec3d(0, 0, -u.body_length)),
                            Vec3d(2 * half, 2 * half, u.body_length), body, kCameraBodyId, true)) {
        r.back = u.body_colour;
        desc_.rects.push_back(r);
      }
      body_rects[ui].second = desc_.rects.size();
    }
    if (pass == 0) world_rects = desc_.rects.size();
  }

  for (const Rect& r : desc_.rects) {
    const Eigen::Matrix3d R = r.world_from_rect.rotation.toRotationMatrix();
    RectFrame fr{r.world_from_rect.translation, R.col(2), R.col(0), R.col(1), {}, {}};
    for (int c = 0; c < 3; ++c)
      fr.flat[c] = fr.centre(c), fr.flat[3 + c] = fr.normal(c), fr.flat[6 + c] = fr.axis_x(c), fr.flat[9 + c] = fr.axis_y(c);
    for (int c = 0; c < 12; ++c) fr.flat_f[c] = static_cast<float>(fr.flat[c]);
    rect_frames_.push_back(fr);
  }

  // Rectangles [first, last) as one quad mesh (primID = index - first), in the world or (frame_from_world given)
  // in that frame.
  const auto attach_quads = [&](RTCScene target, size_t first, size_t last, const Rigid3d* frame_from_world) {
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_QUAD);
    const size_t count = last - first;
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), 4 * count));
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4,
                                                               4 * sizeof(unsigned), count));
    for (size_t i = 0; i < count; ++i) {
      const Rect& r = desc_.rects[first + i];
      HOVS_REQUIRE(r.width > 0 && r.height > 0 && std::isfinite(r.width) && std::isfinite(r.height), "scene object",
                   "rectangle ", first + i, " has a non-positive size");
      const double hw = 0.5 * r.width, hh = 0.5 * r.height;
      const Vec3d corners[4] = {Vec3d(-hw, -hh, 0), Vec3d(hw, -hh, 0), Vec3d(hw, hh, 0), Vec3d(-hw, hh, 0)};
      for (int k = 0; k < 4; ++k) {
        const Vec3d w = frame_from_world ? Vec3d(*frame_from_world * (r.world_from_rect * corners[k]))
                                         : Vec3d(r.world_from_rect * corners[k]);
        for (int c = 0; c < 3; ++c) v[(4 * i + k) * 3 + c] = static_cast<float>(w(c));
        idx[4 * i + k] = static_cast<unsigned>(4 * i + k);
      }
    }
    rtcSetGeometryMask(g, 1u);
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(target, g);
    rtcReleaseGeometry(g);
    return id;
  };
  // All rectangles of the world: one quad mesh; primID = index into rects.
  if (world_rects > 0) rect_geom_ = attach_quads(scene_, 0, world_rects, nullptr);

  // An analytic shape attached to target (the world, or a moving unit's scene: instanced); its slot in user_ and
  // its id in target.
  const auto attach = [&](std::unique_ptr<UserGeometry> ug, RTCScene target, bool instanced) {
    ug->Prepare(instanced);
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, 1);
    rtcSetGeometryUserData(g, ug.get());
    rtcSetGeometryBoundsFunction(g, UserBounds, nullptr);
    rtcSetGeometryIntersectFunction(g, UserIntersect);
    rtcSetGeometryOccludedFunction(g, UserOccluded);
    const bool lens_face = ug->kind == UserGeometry::Kind::kAnnulus && ug->object_id == kCameraBodyId;
    const bool mount = ug->kind == UserGeometry::Kind::kAnnulus && ug->object_id == kMountId;
    rtcSetGeometryMask(g, ug->kind == UserGeometry::Kind::kMirror ? MirrorMaskBit(ug->unit)
                          : lens_face                             ? LensMaskBit(ug->unit)
                          : mount                                 ? MountMaskBit(ug->unit)
                                                                  : 1u);
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(target, g);
    rtcReleaseGeometry(g);
    user_.push_back(std::move(ug));
    return std::make_pair(static_cast<int>(user_.size() - 1), id);
  };
  // Registers a shape under its scene-wide id.
  const auto record = [&](int slot, unsigned id) {
    const UserGeometry& ug = *user_[slot];
    if (ug.kind == UserGeometry::Kind::kAnnulus && ug.object_id == kMountId && ug.unit >= 0 && ug.unit < kMaskUnits) {
      if (own_mount_.size() <= static_cast<size_t>(ug.unit)) own_mount_.resize(ug.unit + 1);
      own_mount_[ug.unit] = {&ug, id};
    }
    if (geom_to_user_.size() <= id) geom_to_user_.resize(id + 1, -1);
    geom_to_user_[id] = slot;
  };
  // The time Embree's ray time [0, 1] spans (AttachMovingUnit): kMaxExposureTime, shorter when a unit turns so fast
  // that its instance would need more time steps than Embree takes.
  for (size_t ui = 0; ui < desc_.units.size(); ++ui) {
    const double rate = desc_.units[ui].angular_velocity.norm();
    if (moving[ui] && rate > 0) motion_horizon_ = std::min(motion_horizon_, kMaxMotionSegments * kMotionSegmentAngle / rate);
  }
  unsigned next_id = rect_geom_ == RTC_INVALID_GEOMETRY_ID ? 0u : rect_geom_ + 1;   // past the world's ids
  for (size_t ui = 0; ui < desc_.units.size(); ++ui) {
    CatadioptricUnit& u = desc_.units[ui];
    if (u.mount_outer_radius <= 0) u.mount_outer_radius = DefaultMountRadius(u);
    const bool instanced = moving[ui] != 0;
    // A moving unit's parts live in its mirror frame (the instance's frame) and move with it.
    RTCScene target = scene_;
    if (instanced) {
      target = rtcNewScene(device_);
      rtcSetSceneBuildQuality(target, RTC_BUILD_QUALITY_HIGH);
      rtcSetSceneFlags(target, RTC_SCENE_FLAG_ROBUST);
    }
    const Rigid3d mirror_from_world = u.world_from_mirror.Inverse();
    MotionInstance mi;
    if (instanced) {
      mi.rect_base = static_cast<unsigned>(body_rects[ui].first);
      mi.quad_geom = attach_quads(target, body_rects[ui].first, body_rects[ui].second, &mirror_from_world);
    }
    auto mirror = std::make_unique<UserGeometry>();
    mirror->kind = UserGeometry::Kind::kMirror;
    mirror->object_id = kMirrorId;
    mirror->unit = static_cast<int>(ui);
    mirror->mirror = u.rig.mirror;
    mirror->world_from_local = u.world_from_mirror;
    mirror->local_from_world = u.world_from_mirror.Inverse();
    mirror->back_colour = u.mirror_back_colour;
    auto mount = std::make_unique<UserGeometry>();
    mount->kind = UserGeometry::Kind::kAnnulus;
    mount->object_id = kMountId;
    mount->unit = static_cast<int>(ui);
    mount->r_inner = u.rig.mirror.RimRadius();
    mount->r_outer = u.mount_outer_radius;
    mount->world_from_local = u.world_from_mirror * Rigid3d::Translation(Vec3d(0, 0, u.rig.mirror.RimZ()));
    mount->local_from_world = mount->world_from_local.Inverse();
    mount->colour = mount->back_colour = u.mount_colour;
    auto lens = std::make_unique<UserGeometry>();
    lens->kind = UserGeometry::Kind::kAnnulus;
    lens->object_id = kCameraBodyId;
    lens->unit = static_cast<int>(ui);
    lens->r_inner = 0;
    lens->r_outer = u.rig.occluder_radius;
    lens->world_from_local = u.world_from_mirror * u.rig.cam_from_mirror.Inverse();
    lens->local_from_world = lens->world_from_local.Inverse();
    lens->colour = lens->back_colour = u.body_colour;
    for (auto* part : {&mirror, &mount, &lens}) {
      if (instanced) (*part)->ray_from_local = mirror_from_world * (*part)->world_from_local;
      const auto [slot, id] = attach(std::move(*part), target, instanced);
      if (!instanced) {
        record(slot, id);
        next_id = std::max(next_id, id + 1);
        continue;
      }
      if (mi.geom.size() <= id) mi.geom.resize(id + 1, RTC_INVALID_GEOMETRY_ID);
      mi.geom[id] = static_cast<unsigned>(slot);   // a slot for now; the scene-wide id below
      if (part == &mount) mi.mount_inner = id;
      if (part == &lens) mi.lens_inner = id;
    }
    if (instanced) {
      rtcCommitScene(target);
      OwnPartShapes& own = mi.own;
      own.analytic = ui < static_cast<size_t>(kMaskUnits);
      own.mask = own.analytic ? LensMaskBit(static_cast<int>(ui)) | MountMaskBit(static_cast<int>(ui)) : 0xFFFFFFFFu;
      const Eigen::Matrix3d Rc = u.rig.cam_from_mirror.rotation.toRotationMatrix();
      const Eigen::Matrix3d Rw = mirror_from_world.rotation.toRotationMatrix();
      for (int k = 0; k < 9; ++k) own.shape[k] = Rc.data()[k], own.R_mirror_from_world[k] = Rw.data()[k];
      for (int k = 0; k < 3; ++k)
        own.shape[9 + k] = u.rig.cam_from_mirror.translation(k), own.t_mirror_from_world[k] = mirror_from_world.translation(k);
      own.shape[12] = u.rig.occluder_radius * u.rig.occluder_radius;
      own.shape[13] = u.rig.mirror.RimZ();
      own.shape[14] = u.rig.mirror.RimRadius() * u.rig.mirror.RimRadius();
      own.shape[15] = u.mount_outer_radius * u.mount_outer_radius;
      own.shape[16] = BodyHalfWidth(u), own.shape[17] = u.body_length;
      const unsigned inst = AttachMovingUnit(u, target, own.mask);
      rtcReleaseScene(target);   // the instance holds it
      if (unit_instance_.size() <= ui) unit_instance_.resize(ui + 1, -1);
      unit_instance_[ui] = static_cast<int>(instances_.size());
      next_id = std::max(next_id, inst + 1);
      if (inst_slot_.size() <= inst) inst_slot_.resize(inst + 1, -1);
      inst_slot_[inst] = static_cast<int>(instances_.size());
      instances_.push_back(std::move(mi));
    }
  }
  rtcCommitScene(scene_);
  // The moving units' shapes get scene-wide ids past the world's (hits in their instances are mapped to them:
  // MapInstanceHits), and their camera bodies' rectangles the world's quad id (there may be no world quads).
  if (!instances_.empty() && rect_geom_ == RTC_INVALID_GEOMETRY_ID) rect_geom_ = next_id++;
  for (MotionInstance& mi : instances_) {
    for (unsigned& g : mi.geom) {
      if (g == RTC_INVALID_GEOMETRY_ID) continue;
      const unsigned id = next_id++;
      record(static_cast<int>(g), id);
      g = id;
    }
    mi.own.lens_geom = mi.geom[mi.lens_inner], mi.own.mount_geom = mi.geom[mi.mount_inner];
  }
  DecideMountPaths(body_rects);
}

// A moving unit's scene (its parts in its mirror frame) as an instance whose transform is its world_from_mirror
// at the ray's time: Embree interpolates it between time steps spread over [0, motion_horizon_] (ray time tau /
// horizon), the rotation by slerp and the translation linearly. That is the unit's motion (WorldFromMirrorAt: a
// constant turn about a fixed axis through the viewpoint, a constant velocity) exactly, in Embree's single
// precision, as long as no step turns by half a turn or more; the steps turn by a quarter turn at most.
unsigned RayScene::AttachMovingUnit(const CatadioptricUnit& u, RTCScene unit_scene, unsigned mask) {
  const double rate = u.angular_velocity.norm();
  const int segments = static_cast<int>(
      std::clamp(std::ceil(rate * motion_horizon_ / kMotionSegmentAngle - 1e-9), 1.0, double(kMaxMotionSegments)));
  RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
  rtcSetGeometryInstancedScene(g, unit_scene);
  rtcSetGeometryTimeStepCount(g, static_cast<unsigned>(segments + 1));
  Eigen::Quaterniond previous = Eigen::Quaterniond::Identity();
  for (int step = 0; step <= segments; ++step) {
    const Rigid3d pose = u.WorldFromMirrorAt(motion_horizon_ * step / segments);
    Eigen::Quaterniond q = pose.rotation.normalized();
    if (step > 0 && q.dot(previous) < 0) q.coeffs() *= -1;   // the short way round between steps
    previous = q;
    RTCQuaternionDecomposition qd;
    rtcInitQuaternionDecomposition(&qd);
    rtcQuaternionDecompositionSetQuaternion(&qd, static_cast<float>(q.w()), static_cast<float>(q.x()),
                                            static_cast<float>(q.y()), static_cast<float>(q.z()));
    rtcQuaternionDecompositionSetTranslation(&qd, static_cast<float>(pose.translation.x()),
                                             static_cast<float>(pose.translation.y()),
                                             static_cast<float>(pose.translation.z()));
    rtcSetGeometryTransformQuaternion(g, static_cast<unsigned>(step), &qd);
  }
  rtcSetGeometryMask(g, mask);
  rtcCommitGeometry(g);
  const unsigned id = rtcAttachGeometry(scene_, g);
  rtcReleaseGeometry(g);
  return id;
}

void RayScene::MapInstanceHits(int n, const unsigned* inst, unsigned* geom, unsigned* prim) const {
  // Most lanes hit nothing inside an instance (a moving unit's parts fill little of a frame): one vectorised test.
  unsigned any = 0;
  for (int i = 0; i < n; ++i) any |= inst[i] ^ RTC_INVALID_GEOMETRY_ID;
  if (!any) return;
  for (int i = 0; i < n; ++i) {
    if (inst[i] == RTC_INVALID_GEOMETRY_ID || geom[i] == RTC_INVALID_GEOMETRY_ID) continue;
    const int slot = inst[i] < inst_slot_.size() ? inst_slot_[inst[i]] : -1;
    if (slot < 0) {   // (no other instances exist)
      geom[i] = RTC_INVALID_GEOMETRY_ID;
      continue;
    }
    const MotionInstance& m = instances_[slot];
    if (geom[i] == m.quad_geom) {
      geom[i] = rect_geom_, prim[i] += m.rect_base;
    } else {
      geom[i] = geom[i] < m.geom.size() ? m.geom[geom[i]] : RTC_INVALID_GEOMETRY_ID;
      prim[i] = 0;
    }
  }
}

// A unit's straight camera rays start at its camera centre (thin-lens samples: a point of the aperture, within
// kMaxApertureRadius of it) and end on its mount ring: they stay inside the box bounding the centre's cube of that
// half-size and the ring's square.
// Anything else whose box overlaps that box (another rectangle, another unit's parts) could be in between;
// the unit's own mirror and lens face are masked off for these rays and its camera body lies behind the lens
// face (the rays go forward from it), so they do not count.
namespace {

// The world box that points given in a unit's mirror frame sweep over [0, T] (its motion: a turn about its
// viewpoint at a constant rate and a constant velocity; at T = 0 where they are at time 0). Sampled at steps of at
// most 0.05 rad of turn: between two steps a point at distance rho from the viewpoint strays from the chord by
// rho (1 - cos(a / 2)) <= rho a^2 / 8 for a step of a rad (the translation is linear), and the box of the steps'
// points holds every chord.
Eigen::AlignedBox3d SweptBox(const CatadioptricUnit& unit, const std::vector<Vec3d>& mirror_points, double T) {
  const double rate = unit.angular_velocity.norm();
  const bool moves = T > 0 && unit.Moves();
  const int steps = moves ? std::max(1, static_cast<int>(std::ceil(rate * T / 0.05))) : 0;
  Eigen::AlignedBox3d box;
  double rho = 0;
  for (const Vec3d& p : mirror_points) rho = std::max(rho, p.norm());
  for (int k = 0; k <= steps; ++k) {
    const Rigid3d w = unit.WorldFromMirrorAt(steps > 0 ? T * k / steps : 0.0);
    for (const Vec3d& p : mirror_points) box.extend(w * p);
  }
  const double a = steps > 0 ? rate * T / steps : 0.0, pad = rho * a * a / 8 + 1e-9;
  return Eigen::AlignedBox3d(box.min() - Vec3d::Constant(pad), box.max() + Vec3d::Constant(pad));
}

}  // namespace

bool RayScene::PathClearOver(size_t u, double T) const {
  const OwnMount& m = own_mount_[u];
  const CatadioptricUnit& unit = desc_.units[u];
  const bool swept = T > 0 && unit.Moves();
  Eigen::AlignedBox3d region;
  // The camera centre and any aperture point around it (thin-lens samples leave those); the ring's corners.
  const Vec3d centre_m = unit.rig.cam_from_mirror.Inverse().translation;
  const double r = m.geometry->r_outer;
  std::vector<Vec3d> corners;
  for (int k = 0; k < 4; ++k) corners.push_back(m.geometry->world_from_local * Vec3d((k & 1) ? r : -r, (k & 2) ? r : -r, 0));
  if (!swept) {
    const Vec3d centre = unit.world_from_mirror * centre_m;
    region.extend(centre - Vec3d::Constant(kMaxApertureRadius)).extend(centre + Vec3d::Constant(kMaxApertureRadius));
    for (const Vec3d& c : corners) region.extend(c);
  } else {
    const Rigid3d mirror_from_world = unit.world_from_mirror.Inverse();
    std::vector<Vec3d> points{centre_m};
    const Eigen::AlignedBox3d centres = SweptBox(unit, points, T);
    region.extend(centres.min() - Vec3d::Constant(kMaxApertureRadius))
        .extend(centres.max() + Vec3d::Constant(kMaxApertureRadius));
    points.clear();
    for (const Vec3d& c : corners) points.push_back(mirror_from_world * c);
    region.extend(SweptBox(unit, points, T));
  }
  region.extend(region.min() - Vec3d::Constant(1e-6)).extend(region.max() + Vec3d::Constant(1e-6));
  // Another unit's parts (its camera body's rectangles, its analytic shapes) move with it: their boxes swept too.
  const auto owner_moves = [&](int w) { return T > 0 && w >= 0 && desc_.units[w].Moves(); };
  const auto world_box = [&](int w, const Eigen::AlignedBox3d& at_zero) {
    if (!owner_moves(w)) return at_zero;
    const Rigid3d mirror_from_world = desc_.units[w].world_from_mirror.Inverse();
    std::vector<Vec3d> points;
    for (int k = 0; k < 8; ++k) points.push_back(mirror_from_world * at_zero.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k)));
    return SweptBox(desc_.units[w], points, T);
  };
  for (size_t i = 0; i < desc_.rects.size(); ++i) {
    if (i >= body_rects_[u].first && i < body_rects_[u].second) continue;
    int owner = -1;
    for (size_t w = 0; w < body_rects_.size(); ++w)
      if (i >= body_rects_[w].first && i < body_rects_[w].second) owner = static_cast<int>(w);
    const Rect& rect = desc_.rects[i];
    Eigen::AlignedBox3d box;
    for (int k = 0; k < 4; ++k)
      box.extend(rect.world_from_rect * Vec3d((k & 1) ? 0.5 * rect.width : -0.5 * rect.width,
                                              (k & 2) ? 0.5 * rect.height : -0.5 * rect.height, 0));
    if (world_box(owner, box).intersects(region)) return false;
  }
  for (const auto& g : user_) {
    if (g->unit == static_cast<int>(u)) continue;  // its mirror, lens face and mount ring
    RTCBounds b;
    g->Bounds(g->world_from_local, &b);
    const Eigen::AlignedBox3d box(Vec3d(b.lower_x, b.lower_y, b.lower_z), Vec3d(b.upper_x, b.upper_y, b.upper_z));
    if (world_box(g->unit, box).intersects(region)) return false;
  }
  return true;
}

void RayScene::DecideMountPaths(const std::vector<std::pair<size_t, size_t>>& body_rects) {
  body_rects_ = body_rects;
  for (size_t u = 0; u < own_mount_.size(); ++u)
    if (own_mount_[u].geometry) own_mount_[u].path_clear = PathClearOver(u, 0.0);
}

bool RayScene::MountPathClearDuring(int unit, double exposure) const {
  if (!MountPathClear(unit)) return false;
  if (!(exposure > 0)) return true;
  bool any = false;
  for (const CatadioptricUnit& u : desc_.units) any = any || u.Moves();
  return !any || PathClearOver(static_cast<size_t>(unit), exposure);
}

bool RayScene::MountPathClear(int unit) const {
  return unit >= 0 && static_cast<size_t>(unit) < own_mount_.size() && own_mount_[unit].path_clear;
}

RayScene::~RayScene() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

void RayScene::Shade(const Vec3d& o, const Vec3d& d, unsigned geom_id, unsigned prim_id, Hit* h, bool colour) const {
  if (geom_id == rect_geom_) {
    const Rect& r = desc_.rects[prim_id];
    const RectFrame& fr = rect_frames_[prim_id];
    const Vec3d& n = fr.normal;
    const double denom = d.dot(n);
    if (denom == 0) return;
    const double t = (fr.centre - o).dot(n) / denom;
    const Vec3d X = o + t * d;
    const Vec2d local(fr.axis_x.dot(X - fr.centre), fr.axis_y.dot(X - fr.centre));
    const bool front = denom < 0;
    h->hit = true;
    h->object_id = r.object_id;
    h->t = t;
    h->point = X;
    h->normal = front ? n : Vec3d(-n);
    if (colour) h->colour = front || r.double_sided ? r.front.Eval(local.x(), local.y()) : r.back;
    return;
  }
  if (geom_id >= geom_to_user_.size() || geom_to_user_[geom_id] < 0) return;
  const UserGeometry& g = *user_[geom_to_user_[geom_id]];
  double t = 0;
  Vec3d n;
  if (!g.Intersect(o, d, 0.0, HUGE_VAL, &t, &n)) {
    // Embree's float ray and the double ray disagree at a silhouette: take the float distance.
    n = Vec3d(0, 0, 1);
  }
  UserHit(g, o, d, t, n, h);
  (void)prim_id;
}

void RayScene::UserHit(const UserGeometry& g, const Vec3d& o, const Vec3d& d, double t, const Vec3d& n, Hit* h) {
  h->hit = true;
  h->object_id = g.object_id;
  h->unit = g.unit;
  h->t = t;
  h->point = o + t * d;
  h->normal = d.dot(n) < 0 ? n : Vec3d(-n);
  h->colour = g.kind == UserGeometry::Kind::kMirror ? g.back_colour : g.colour;
}

namespace {
// Fills a 16-wide packet (lanes past count are masked off) and intersects it with the scene.
// Lane i of a packet, everything but origin and direction: tnear, an infinite tfar, the Embree mask of the
// ray's origin (see RayMask), and the id, which carries the unit whose (convex) mirror the ray leaves (the
// mirror callback skips it; -1: none).
template <class RayHitW>
void SetLane(RayHitW* rh, int i, float tnear, int from_mirror, int from_camera) {
  rh->ray.tnear[i] = tnear;
  rh->ray.tfar[i] = std::numeric_limits<float>::infinity();
  rh->ray.mask[i] = RayMask(from_mirror, from_camera), rh->ray.flags[i] = 0, rh->ray.time[i] = 0;
  rh->ray.id[i] = static_cast<unsigned>(std::max(from_mirror, -1) + 1);
  rh->hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
  rh->hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
}

// Traces a filled packet (rtcIntersect8 or rtcIntersect16), rays flagged coherent.
template <class RayHitW, class IntersectW>
void TracePacket(RTCScene scene, const int* valid, RayHitW* rh, IntersectW intersect) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  intersect(valid, scene, &ctx, rh);
}

template <int W, class RayHitW, class IntersectW>
void IntersectPacketW(RTCScene scene, int count, const Vec3d* o, const Vec3d* d, const double* tnear,
                      const int* from_mirror, RayHitW* rh, IntersectW intersect) {
  alignas(64) int valid[W];
  for (int i = 0; i < W; ++i) {
    valid[i] = i < count ? -1 : 0;
    const int k = i < count ? i : 0;
    rh->ray.org_x[i] = static_cast<float>(o[k].x()), rh->ray.org_y[i] = static_cast<float>(o[k].y());
    rh->ray.org_z[i] = static_cast<float>(o[k].z());
    rh->ray.dir_x[i] = static_cast<float>(d[k].x()), rh->ray.dir_y[i] = static_cast<float>(d[k].y());
    rh->ray.dir_z[i] = static_cast<float>(d[k].z());
    SetLane(rh, i, static_cast<float>(tnear ? tnear[k] : 0.0), from_mirror ? from_mirror[k] : -1, -1);
  }
  TracePacket(scene, valid, rh, intersect);
}

void IntersectPacket(RTCScene scene, int count, const Vec3d* o, const Vec3d* d, const double* tnear,
                     const int* from_mirror, RTCRayHit16* rh) {
  IntersectPacketW<16>(scene, count, o, d, tnear, from_mirror, rh, rtcIntersect16);
}
}  // namespace

void RayScene::Trace16(int count, const Vec3d* o, const Vec3d* d, const double* tnear, Hit* hits,
                       const int* from_mirror, bool colour) const {
  alignas(64) RTCRayHit16 rh;
  IntersectPacket(scene_, count, o, d, tnear, from_mirror, &rh);
  if (!instances_.empty()) MapInstanceHits(count, rh.hit.instID[0], rh.hit.geomID, rh.hit.primID);
  for (int i = 0; i < count; ++i) {
    Hit& h = hits[i];
    h = Hit();
    if (rh.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) {
      if (colour) h.colour = desc_.sky.Eval(d[i]);
      continue;
    }
    Shade(o[i], d[i], rh.hit.geomID[i], rh.hit.primID[i], &h, colour);
  }
}

// The Embree lanes of a whole batch, set up once before its packets are traced.
//
// A unit's straight camera rays (they missed its mirror within the rim: 40 % of a frame's samples, the image
// past the rim) end on its mount ring unless something lies in between. They meet the ring analytically, in
// double (RayBatch::mount_t, from the renderer's ray set-up in the mirror frame where the rim test was made, or
// here with the ring's own test), and go to Embree only up to that distance with the ring masked off: anything
// nearer still wins, and the ring's callback is not called for them. Where nothing can be in between
// (OwnMount::path_clear) they do not go to Embree at all; a packet of such rays only gets its hits.
struct BatchLanes {
  alignas(64) int valid[RayBatch::kMax];         // -1: traced by Embree, 0: not
  alignas(64) float tfar[RayBatch::kMax];        // > 0: traced only up to here (the ring's distance)
  alignas(64) unsigned mask_off[RayBatch::kMax]; // Embree mask bits cleared (the ring's)
  alignas(64) unsigned mount_geom[RayBatch::kMax];  // the ring that ends the ray where Embree finds nothing, or
                                                    // RTC_INVALID_GEOMETRY_ID
};

namespace {

// Packet fields of w full lanes from batch arrays (already offset to the packet's first ray): the conversions
// to float (copies for T = float), the masks (RayMask less mask_off) and ids; tfar is infinite except where
// tfar_in > 0.
// W: the packet width, a constant (for T = float the conversions are copies, which GCC otherwise turns into a
// library memcpy call each).
template <class T, int W>
HOVS_VECTOR_CLONES void FillPacket(const T* __restrict ox, const T* __restrict oy, const T* __restrict oz,
                const T* __restrict dx, const T* __restrict dy, const T* __restrict dz,
                const float* __restrict tnear, const int* __restrict from_mirror, const int* __restrict from_camera,
                const float* __restrict tfar_in, const unsigned* __restrict mask_off, float* __restrict org_x,
                float* __restrict org_y, float* __restrict org_z, float* __restrict dir_x, float* __restrict dir_y,
                float* __restrict dir_z, float* __restrict tnear_out, float* __restrict tfar, unsigned* __restrict mask,
                unsigned* __restrict id, unsigned* __restrict flags, float* __restrict time, unsigned* __restrict geom,
                unsigned* __restrict inst) {
  for (int i = 0; i < W; ++i) {
    org_x[i] = static_cast<float>(ox[i]), org_y[i] = static_cast<float>(oy[i]), org_z[i] = static_cast<float>(oz[i]);
    dir_x[i] = static_cast<float>(dx[i]), dir_y[i] = static_cast<float>(dy[i]), dir_z[i] = static_cast<float>(dz[i]);
    tnear_out[i] = tnear[i];
    tfar[i] = tfar_in[i] > 0 ? tfar_in[i] : std::numeric_limits<float>::infinity();
    mask[i] = RayMask(from_mirror[i], from_camera[i]) & ~mask_off[i];
    id[i] = from_mirror[i] >= 0 ? static_cast<unsigned>(from_mirror[i]) + 1 : 0u;
    flags[i] = 0, time[i] = 0;
    geom[i] = RTC_INVALID_GEOMETRY_ID, inst[i] = RTC_INVALID_GEOMETRY_ID;
  }
}


// The common case of PrepareLanes without branches: every straight camera ray of the batch leaves unit U's
// camera with its ring distance computed.
template <class T>
HOVS_VECTOR_CLONES void RingLanes(int n, const unsigned char* __restrict bvalid, const int* __restrict from_camera,
               const T* __restrict mount_t, int U, unsigned bit, int clear, int* __restrict valid,
               float* __restrict tfar, unsigned* __restrict mask_off, unsigned ring_geom, unsigned* __restrict mount_geom) {
  const int match = U >= 0 ? U : -1000;   // no unit: no lane is a ring lane
  // As 0 / 1 arithmetic, not selects: GCC 12 vectorises the selects here only with a branch per vector.
  for (int i = 0; i < n; ++i) {
    const T t = mount_t[i];
    const int live = bvalid[i] != 0;
    const int ring = live & (from_camera[i] == match) & (t > 0);
    tfar[i] = static_cast<float>(t) * static_cast<float>(ring);   // 0 (or -0) where not a ring lane
    mask_off[i] = bit & static_cast<unsigned>(-ring);
    mount_geom[i] = ring_geom | static_cast<unsigned>(ring - 1);   // ring ? ring_geom : RTC_INVALID_GEOMETRY_ID
    valid[i] = -(live & (1 - (ring & clear)));   // nothing in between: no Embree for this lane
  }
}

// The unit of a batch's straight camera rays (the largest from_camera; -1: none) and whether every straight ray
// is that unit's with its ring distance computed (uniform): one pass without branches.
template <class T>
HOVS_VECTOR_CLONES int CameraLanes(int n, const int* __restrict from_camera, const T* __restrict mount_t,
                                   bool* uniform) {
  int U = -1;
  for (int i = 0; i < n; ++i) U = std::max(U, from_camera[i]);
  int odd = 0;
  for (int i = 0; i < n; ++i) odd |= (from_camera[i] >= 0) & ((from_camera[i] != U) | !(mount_t[i] >= 0));
  *uniform = odd == 0;
  return U;
}

template <class T>
void PrepareLanes(const RayBatchOf<T>& b, const std::vector<RayScene::OwnMount>& mounts, BatchLanes* L) {
  const int n = b.n;
  bool uniform = false;
  const int U = CameraLanes(n, b.from_camera, b.mount_t, &uniform);
  uniform = uniform && U >= 0 && static_cast<size_t>(U) < mounts.size() && mounts[U].geometry != nullptr;
  if (uniform || U < 0) {   // U < 0: no straight camera ray at all (no lane is a ring lane)
    RingLanes(n, b.valid, b.from_camera, b.mount_t, U, U >= 0 ? MountMaskBit(U) : 0u,
              U >= 0 && mounts[U].path_clear && b.mount_paths_clear ? 1 : 0, L->valid, L->tfar, L->mask_off,
              U >= 0 ? mounts[U].geom_id : RTC_INVALID_GEOMETRY_ID, L->mount_geom);
    return;
  }
  for (int j = 0; j < n; ++j) {
    L->valid[j] = b.valid[j] ? -1 : 0;
    L->tfar[j] = 0, L->mask_off[j] = 0, L->mount_geom[j] = RTC_INVALID_GEOMETRY_ID;
    const int u = b.from_camera[j];
    if (!b.valid[j] || u < 0 || static_cast<size_t>(u) >= mounts.size() || !mounts[u].geometry) continue;
    double t = b.mount_t[j];
    if (t < 0 && !mounts[u].geometry->Intersect(Vec3d(b.ox[j], b.oy[j], b.oz[j]), Vec3d(b.dx[j], b.dy[j], b.dz[j]),
                                                b.tnear[j], HUGE_VAL, &t, nullptr))
      continue;
    if (t <= 0) continue;
    L->tfar[j] = static_cast<float>(t);
    L->mask_off[j] = MountMaskBit(u);
    L->mount_geom[j] = mounts[u].geom_id;
    // Nothing can be in between (and the ray starts at the camera centre, as the path test assumes).
    if (mounts[u].path_clear && b.mount_paths_clear && b.mount_t[j] > 0) L->valid[j] = 0;
  }
}

// Batch rays [i0, i0 + W) (fewer at the end) as one Embree packet of width W (RTCRayHit8 or RTCRayHit16).
// Rays with times (b.timed) take time = b.time * inv_horizon in Embree's [0, 1] (a moving unit's instance); the
// hits' instance ids go to inst_ids when it is given (the scene has moving units), else they are not needed.
template <int W, class RayHitW, class T, class IntersectW>
void TracePacketOfBatch(RTCScene scene, const RayBatchOf<T>& b, const BatchLanes& L, int i0, unsigned* geom_ids,
                        unsigned* prim_ids, unsigned* inst_ids, float inv_horizon, IntersectW intersect) {
  const int count = std::min(W, b.n - i0);
  int any = 0;
  if (count == W) {   // (as vectors of four lanes: GCC leaves the plain loop scalar)
    typedef int Lanes4 __attribute__((vector_size(16)));
    Lanes4 acc = {0, 0, 0, 0};
    for (int i = 0; i < W; i += 4) {
      Lanes4 x;
      std::memcpy(&x, L.valid + i0 + i, sizeof x);
      acc |= x;
    }
    any = acc[0] | acc[1] | acc[2] | acc[3];
  } else {
    for (int i = 0; i < count; ++i) any |= L.valid[i0 + i];
  }
  if (!any) {   // every lane ends on its ring or is invalid: ResolveMisses gives them the ring
    if (count == W) {   // (a constant size: vector stores, not library calls)
      for (int i = 0; i < W; ++i) geom_ids[i] = RTC_INVALID_GEOMETRY_ID;   // (two loops: the arrays may alias)
      for (int i = 0; i < W; ++i) prim_ids[i] = 0u;
    } else {
      std::fill(geom_ids, geom_ids + count, RTC_INVALID_GEOMETRY_ID);
      std::fill(prim_ids, prim_ids + count, 0u);
    }
    if (inst_ids) std::fill(inst_ids, inst_ids + count, RTC_INVALID_GEOMETRY_ID);
    return;
  }
  alignas(64) RayHitW rh;
  alignas(64) int partial_valid[W];
  const int* valid = L.valid + i0;   // 64-byte aligned for W = 16 (i0 a multiple of 16), 32-byte for W = 8
  if (count == W) {
    FillPacket<T, W>(b.ox + i0, b.oy + i0, b.oz + i0, b.dx + i0, b.dy + i0, b.dz + i0, b.tnear + i0, b.from_mirror + i0,
               b.from_camera + i0, L.tfar + i0, L.mask_off + i0, rh.ray.org_x, rh.ray.org_y, rh.ray.org_z,
               rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z, rh.ray.tnear, rh.ray.tfar, rh.ray.mask, rh.ray.id,
               rh.ray.flags, rh.ray.time, rh.hit.geomID, rh.hit.instID[0]);
  } else {
    // Lanes past count repeat the batch's ray i0, masked off.
    for (int i = 0; i < W; ++i) {
      const int j = i0 + (i < count ? i : 0);
      partial_valid[i] = i < count ? L.valid[j] : 0;
      rh.ray.org_x[i] = static_cast<float>(b.ox[j]), rh.ray.org_y[i] = static_cast<float>(b.oy[j]);
      rh.ray.org_z[i] = static_cast<float>(b.oz[j]);
      rh.ray.dir_x[i] = static_cast<float>(b.dx[j]), rh.ray.dir_y[i] = static_cast<float>(b.dy[j]);
      rh.ray.dir_z[i] = static_cast<float>(b.dz[j]);
      SetLane(&rh, i, b.tnear[j], b.from_mirror[j], b.from_camera[j]);
      if (L.tfar[j] > 0) rh.ray.tfar[i] = L.tfar[j];
      rh.ray.mask[i] &= ~L.mask_off[j];
    }
    valid = partial_valid;
  }
  if (b.timed) {
    for (int i = 0; i < W; ++i) {
      const int j = i0 + (i < count ? i : 0);
      rh.ray.time[i] = std::min(std::max(b.time[j] * inv_horizon, 0.0f), 1.0f);
    }
  }
  TracePacket(scene, valid, &rh, intersect);
  if (inst_ids && count == W) {   // (a constant size: vector moves, not a library call)
    std::memcpy(inst_ids, rh.hit.instID[0], sizeof(unsigned) * W);
  } else if (inst_ids) {
    std::memcpy(inst_ids, rh.hit.instID[0], sizeof(unsigned) * static_cast<size_t>(count));
  }
  if (count == W) {   // (a constant size: vector moves, not a library call)
    std::memcpy(geom_ids, rh.hit.geomID, sizeof(unsigned) * W);
    std::memcpy(prim_ids, rh.hit.primID, sizeof(unsigned) * W);
  } else {
    std::memcpy(geom_ids, rh.hit.geomID, sizeof(unsigned) * static_cast<size_t>(count));
    std::memcpy(prim_ids, rh.hit.primID, sizeof(unsigned) * static_cast<size_t>(count));
  }
}

// After the packets of a batch: a lane Embree found nothing for ends on its ring, if it has one (prim 0; a
// miss's prim is never read otherwise).
HOVS_VECTOR_CLONES void ResolveMisses(int n, const unsigned* __restrict mount_geom, unsigned* __restrict geom_ids,
                                      unsigned* __restrict prim_ids) {
  for (int i = 0; i < n; ++i) {
    const bool miss = geom_ids[i] == RTC_INVALID_GEOMETRY_ID;
    geom_ids[i] = miss ? mount_geom[i] : geom_ids[i];
    prim_ids[i] = miss ? 0u : prim_ids[i];
  }
}

}  // namespace

namespace {

// Rays from the world to a frame: o' = R o + t, d' = R d (R column-major). Vectorised.
template <class T>
HOVS_VECTOR_CLONES void RaysToFrame(int n, const double* __restrict Rd, const double* __restrict td,
                                    const T* __restrict ox, const T* __restrict oy, const T* __restrict oz,
                                    const T* __restrict dx, const T* __restrict dy, const T* __restrict dz,
                                    T* __restrict fox, T* __restrict foy, T* __restrict foz, T* __restrict fdx,
                                    T* __restrict fdy, T* __restrict fdz) {
  T R[9], t[3];
  for (int k = 0; k < 9; ++k) R[k] = static_cast<T>(Rd[k]);
  for (int k = 0; k < 3; ++k) t[k] = static_cast<T>(td[k]);
  for (int i = 0; i < n; ++i) {
    const T o0 = ox[i], o1 = oy[i], o2 = oz[i], d0 = dx[i], d1 = dy[i], d2 = dz[i];
    fox[i] = R[0] * o0 + R[3] * o1 + R[6] * o2 + t[0];
    foy[i] = R[1] * o0 + R[4] * o1 + R[7] * o2 + t[1];
    foz[i] = R[2] * o0 + R[5] * o1 + R[8] * o2 + t[2];
    fdx[i] = R[0] * d0 + R[3] * d1 + R[6] * d2;
    fdy[i] = R[1] * d0 + R[4] * d1 + R[7] * d2;
    fdz[i] = R[2] * d0 + R[5] * d1 + R[8] * d2;
  }
}

// The nearest of a moving unit's own parts along its rays in its mirror frame (OwnPartShapes): part[i] = 0 none,
// 1 the lens face, 2 the mount ring, 3 + f the body's rectangle f (MakeBox's order: top, bottom, +x, -x, +y, -y),
// at distance t[i] beyond tnear[i], for lanes with active[i]. The disc and annulus as UserGeometry's tests (a
// plane, then the radius), the box by slabs in the camera frame (where the ray enters it). A ray parallel to a
// plane gives an infinite or undefined distance, which no comparison passes. Vectorised. sh: R_cam_from_mirror
// (9, column-major), t_cam_from_mirror (3), lens_r2, rim_z, rim_r2, mount_r2, half, length.
template <class T>
HOVS_VECTOR_CLONES void OwnPartLanes(int n, const unsigned char* __restrict active, const T* __restrict ox_in,
                                     const T* __restrict oy_in, const T* __restrict oz_in, const T* __restrict dx_in,
                                     const T* __restrict dy_in, const T* __restrict dz_in,
                                     const float* __restrict tnear, const double* __restrict sh, int* __restrict part,
                                     float* __restrict tout) {
  // In single precision whatever the rays' (Embree, which takes the distance, traces in it; which part a ray
  // meets differs from a double-precision test only within about 1e-7 m of a part's edge).
  alignas(64) float ox[RayBatch::kMax], oy[RayBatch::kMax], oz[RayBatch::kMax], dx[RayBatch::kMax],
      dy[RayBatch::kMax], dz[RayBatch::kMax];
  for (int i = 0; i < n; ++i) {
    ox[i] = static_cast<float>(ox_in[i]), oy[i] = static_cast<float>(oy_in[i]), oz[i] = static_cast<float>(oz_in[i]);
    dx[i] = static_cast<float>(dx_in[i]), dy[i] = static_cast<float>(dy_in[i]), dz[i] = static_cast<float>(dz_in[i]);
  }
  using F = float;
  F R[9], c[3];
  for (int k = 0; k < 9; ++k) R[k] = static_cast<F>(sh[k]);
  for (int k = 0; k < 3; ++k) c[k] = static_cast<F>(sh[9 + k]);
  const F lens_r2 = static_cast<F>(sh[12]), rim_z = static_cast<F>(sh[13]), rim_r2 = static_cast<F>(sh[14]);
  const F mount_r2 = static_cast<F>(sh[15]), half = static_cast<F>(sh[16]), length = static_cast<F>(sh[17]);
  const F inf = std::numeric_limits<F>::infinity();
  for (int i = 0; i < n; ++i) {
    const F o0 = ox[i], o1 = oy[i], o2 = oz[i], d0 = dx[i], d1 = dy[i], d2 = dz[i], tn = tnear[i];
    // The camera frame.
    const F cx = R[0] * o0 + R[3] * o1 + R[6] * o2 + c[0], cy = R[1] * o0 + R[4] * o1 + R[7] * o2 + c[1];
    const F cz = R[2] * o0 + R[5] * o1 + R[8] * o2 + c[2];
    const F ex = R[0] * d0 + R[3] * d1 + R[6] * d2, ey = R[1] * d0 + R[4] * d1 + R[7] * d2;
    const F ez = R[2] * d0 + R[5] * d1 + R[8] * d2;
    // The lens face: the disc z = 0 of the camera frame. (Flags as integers combined with &, and selects: the
    // loop then vectorises.)
    const F tl = -cz / ez, lx = cx + tl * ex, ly = cy + tl * ey;
    const int hl = (tl > tn ? 1 : 0) & (lx * lx + ly * ly <= lens_r2 ? 1 : 0);
    // The mount ring: the annulus in the rim plane.
    const F tm = (rim_z - o2) / d2, mx = o0 + tm * d0, my = o1 + tm * d1, mr2 = mx * mx + my * my;
    const int hm = (tm > tn ? 1 : 0) & (mr2 >= rim_r2 ? 1 : 0) & (mr2 <= mount_r2 ? 1 : 0);
    // The body: where the ray enters the box x, y in [-half, half], z in [-length, 0] of the camera frame.
    const F ix = F(1) / ex, iy = F(1) / ey, iz = F(1) / ez;
    const F ax = (-half - cx) * ix, bx = (half - cx) * ix, ay = (-half - cy) * iy, by = (half - cy) * iy;
    const F az = (-length - cz) * iz, bz = -cz * iz;
    const F nx = ax < bx ? ax : bx, fx = ax < bx ? bx : ax, ny = ay < by ? ay : by, fy = ay < by ? by : ay;
    const F nz = az < bz ? az : bz, fz = az < bz ? bz : az;
    const F nxy = nx < ny ? ny : nx, fxy = fx < fy ? fx : fy;
    const F enter = nxy < nz ? nz : nxy, exit = fxy < fz ? fxy : fz;
    const int hb = (enter <= exit ? 1 : 0) & (enter > tn ? 1 : 0);
    const int is_z = enter == nz ? 1 : 0, is_x = (enter == nx ? 1 : 0) & (1 - is_z);
    const int face = is_z * (ez < 0 ? 0 : 1) + is_x * (ex < 0 ? 2 : 3) + (1 - is_z - is_x) * (ey < 0 ? 4 : 5);
    // The nearest (the lens face first where the body's top face lies in its plane).
    F best = hl ? tl : inf;
    int p = hl;
    const int take_m = hm & (tm < best ? 1 : 0);
    p = take_m ? 2 : p;
    best = take_m ? tm : best;
    const int take_b = hb & (enter < best ? 1 : 0);
    p = take_b ? 3 + face : p;
    best = take_b ? enter : best;
    part[i] = active[i] != 0 ? p : 0;
    tout[i] = static_cast<float>(best);
  }
}

}  // namespace

template <class T>
bool RayScene::OwnParts(const RayBatchOf<T>& b, int U, BatchLanes* L, unsigned* own_geom, unsigned* own_prim) const {
  const MotionInstance& m = instances_[unit_instance_[U]];
  const OwnPartShapes& sh = m.own;
  const int n = b.n;
  alignas(64) unsigned char active[RayBatch::kMax];
  for (int i = 0; i < n; ++i) {
    // The unit's own rays skip its instance; those from its mirror meet its parts here. (Its straight camera
    // rays leave the lens face forwards: of its parts only the mount ring lies ahead, which PrepareLanes met.)
    const int from_mirror = b.from_mirror[i] == U ? 1 : 0, own = from_mirror | (b.from_camera[i] == U ? 1 : 0);
    L->mask_off[i] |= sh.mask & static_cast<unsigned>(-own);
    active[i] = static_cast<unsigned char>(from_mirror & (L->valid[i] != 0 ? 1 : 0));
  }
  alignas(64) T fo[6][RayBatch::kMax];
  const T *mox = b.mox, *moy = b.moy, *moz = b.moz, *mdx = b.mdx, *mdy = b.mdy, *mdz = b.mdz;
  if (!b.mirror_frame) {   // rays at time 0: the world rays mapped back
    RaysToFrame<T>(n, sh.R_mirror_from_world, sh.t_mirror_from_world, b.ox, b.oy, b.oz, b.dx, b.dy, b.dz, fo[0],
                   fo[1], fo[2], fo[3], fo[4], fo[5]);
    mox = fo[0], moy = fo[1], moz = fo[2], mdx = fo[3], mdy = fo[4], mdz = fo[5];
  }
  alignas(64) int part[RayBatch::kMax];
  alignas(64) float t[RayBatch::kMax];
  OwnPartLanes<T>(n, active, mox, moy, moz, mdx, mdy, mdz, b.tnear, sh.shape, part, t);
  bool any = false;
  for (int i = 0; i < n; ++i) {
    if (!part[i]) continue;
    any = true;
    L->tfar[i] = t[i];   // the world trace looks only nearer
    own_geom[i] = part[i] == 1 ? sh.lens_geom : part[i] == 2 ? sh.mount_geom : rect_geom_;
    own_prim[i] = part[i] >= 3 ? m.rect_base + static_cast<unsigned>(part[i] - 3) : 0u;
  }
  return any;
}

template <class T>
int RayScene::IntersectBatch(const RayBatchOf<T>& b, unsigned* geom_ids, unsigned* prim_ids) const {
  BatchLanes lanes;
  PrepareLanes(b, own_mount_, &lanes);
  // A moving unit's own rays meet its own parts in its mirror frame (OwnParts), not through its instance.
  alignas(64) unsigned own_geom[RayBatch::kMax], own_prim[RayBatch::kMax];
  bool own = false;
  if (!instances_.empty()) {
    int U = -1;
    for (int i = 0; i < b.n; ++i) U = std::max(U, std::max(b.from_mirror[i], b.from_camera[i]));
    if (OwnPartsInMirrorFrame(U)) {
      std::fill(own_geom, own_geom + b.n, RTC_INVALID_GEOMETRY_ID);
      own = OwnParts(b, U, &lanes, own_geom, own_prim);
    }
  }
  int traced = 0;   // lanes Embree traces (valid -1; 0: ended analytically, or invalid)
  for (int i = 0; i < b.n; ++i) traced -= lanes.valid[i];
  alignas(64) unsigned inst[RayBatch::kMax];
  unsigned* const inst_ids = instances_.empty() ? nullptr : inst;
  const float inv_horizon = static_cast<float>(1.0 / motion_horizon_);
  for (int i0 = 0; i0 < b.n; i0 += native16_ ? 16 : 8) {
    unsigned* const ii = inst_ids ? inst_ids + i0 : nullptr;
    if (native16_) {
      TracePacketOfBatch<16, RTCRayHit16>(scene_, b, lanes, i0, geom_ids + i0, prim_ids + i0, ii, inv_horizon,
                                          rtcIntersect16);
    } else {
      // Without native 16-wide packets (no AVX-512) Embree emulates rtcIntersect16; rtcIntersect8 is faster.
      TracePacketOfBatch<8, RTCRayHit8>(scene_, b, lanes, i0, geom_ids + i0, prim_ids + i0, ii, inv_horizon,
                                        rtcIntersect8);
    }
  }
  if (inst_ids) MapInstanceHits(b.n, inst_ids, geom_ids, prim_ids);
  ResolveMisses(b.n, lanes.mount_geom, geom_ids, prim_ids);
  if (own) {   // nothing in the world nearer than the unit's own part: the part
    for (int i = 0; i < b.n; ++i) {
      if (own_geom[i] == RTC_INVALID_GEOMETRY_ID || geom_ids[i] != RTC_INVALID_GEOMETRY_ID) continue;
      geom_ids[i] = own_geom[i], prim_ids[i] = own_prim[i];
    }
  }
  return traced;
}

namespace {

// Where batch rays i0 .. i0 + m - 1 meet a rectangle's plane, into the same lanes of out: d.n, the distance k
// along d, the point p = o + k d and its (s, t) on the rectangle, axis_x.(p - c) and axis_y.(p - c): the
// operations of the scalar Eigen expressions (Shade; 3-vector dot products sum left to right). f: the
// rectangle's centre c, normal, axis_x, axis_y (RectFrame::flat).
template <class T>
struct RectPlaneRuns {
  alignas(64) T denom[RayBatch::kMax], k[RayBatch::kMax], px[RayBatch::kMax], py[RayBatch::kMax],
      pz[RayBatch::kMax], s[RayBatch::kMax], t[RayBatch::kMax];
};
template <class T>
HOVS_VECTOR_CLONES void RectPlaneHits(int i0, int m, const T* __restrict ox, const T* __restrict oy,
                                      const T* __restrict oz, const T* __restrict dx, const T* __restrict dy,
                                      const T* __restrict dz, const T* __restrict f, RectPlaneRuns<T>* __restrict out) {
  const T cx = f[0], cy = f[1], cz = f[2], nx = f[3], ny = f[4], nz = f[5];
  const T ax = f[6], ay = f[7], az = f[8], bx = f[9], by = f[10], bz = f[11];
  for (int i = i0; i < i0 + m; ++i) {
    const T dn = dx[i] * nx + dy[i] * ny + dz[i] * nz;
    const T k = ((cx - ox[i]) * nx + (cy - oy[i]) * ny + (cz - oz[i]) * nz) / dn;
    const T px = ox[i] + k * dx[i], py = oy[i] + k * dy[i], pz = oz[i] + k * dz[i];
    const T X0 = px - cx, X1 = py - cy, X2 = pz - cz;
    out->denom[i] = dn, out->k[i] = k, out->px[i] = px, out->py[i] = py, out->pz[i] = pz;
    out->s[i] = ax * X0 + ay * X1 + az * X2;
    out->t[i] = bx * X0 + by * X1 + bz * X2;
  }
}

// The sky colour (Sky::Eval) of rays [0, m) from their directions' z, into rgb (3 floats per ray).
template <class T>
HOVS_VECTOR_CLONES void SkyColours(int m, const T* __restrict dz, const float* __restrict horizon,
                                   const float* __restrict zenith, const float* __restrict nadir,
                                   float* __restrict rgb) {
  for (int i = 0; i < m; ++i) {
    const T z = std::clamp(dz[i], T(-1), T(1));
    const bool up = z >= 0;
    const float f = static_cast<float>(std::sqrt(up ? z : -z));
    for (int c = 0; c < 3; ++c) {
      const float a = horizon[c], e = up ? zenith[c] : nadir[c];
      rgb[3 * i + c] = a + f * (e - a);
    }
  }
}

// n copies of colour c, interleaved (rgb[3 k + ch]), 16 at a time from a pattern.
void FillColour(int n, const Rgb& c, float* rgb) {
  float pattern[48];
  for (int k = 0; k < 16; ++k) pattern[3 * k] = c[0], pattern[3 * k + 1] = c[1], pattern[3 * k + 2] = c[2];
  int k = 0;
  for (; k + 16 <= n; k += 16) std::memcpy(rgb + 3 * k, pattern, sizeof pattern);
  std::memcpy(rgb + 3 * k, pattern, sizeof(float) * 3 * static_cast<size_t>(n - k));
}

}  // namespace

namespace {

// Where the lanes of a batch change: brk[k] = 1 where lane k differs from lane k - 1 in validity, geometry or
// primitive (brk[0] = 1), and brk[n] = 1 as a sentinel; vectorised. RunEnd then finds the end of the run that
// starts at lane i with memchr (SIMD in glibc) instead of a scalar loop of three loads and compares per lane.
struct RunBreaks {
  unsigned char brk[RayBatch::kMax + 1];
};
HOVS_VECTOR_CLONES void FindRunBreaks(int n, const unsigned char* __restrict valid, const unsigned* __restrict geom,
                                      const unsigned* __restrict prim, unsigned char* __restrict brk) {
  // In blocks of a constant 32 lanes (the last one overlapping the one before: the same values again), so that
  // the loop is vectorised without a scalar remainder.
  constexpr int kB = 32;
  const auto block = [&](int k0) {
    for (int k = k0; k < k0 + kB; ++k) {
      const int differ = (valid[k] != valid[k - 1]) | (geom[k] != geom[k - 1]) | (prim[k] != prim[k - 1]);
      brk[k] = static_cast<unsigned char>(differ);
    }
  };
  brk[0] = 1;
  if (n > kB) {
    for (int k0 = 1; k0 < n; k0 += kB) block(std::min(k0, n - kB));
  } else {
    for (int k = 1; k < n; ++k) {
      const int differ = (valid[k] != valid[k - 1]) | (geom[k] != geom[k - 1]) | (prim[k] != prim[k - 1]);
      brk[k] = static_cast<unsigned char>(differ);
    }
  }
  brk[n] = 1;
}
// The first lane after i that starts a new run (n at most).
inline int RunEnd(const RunBreaks& r, int i) {
  return static_cast<int>(static_cast<const unsigned char*>(std::memchr(r.brk + i + 1, 1, sizeof r.brk - (i + 1))) -
                          r.brk);
}

}  // namespace

int RayScene::Colours(const RayBatch& b, float* rgb) const { return ColoursOf(b, rgb); }
int RayScene::Colours(const RayBatchF& b, float* rgb) const { return ColoursOf(b, rgb); }

template <class T>
int RayScene::ColoursOf(const RayBatchOf<T>& b, float* rgb) const {
  const int n = b.n;
  unsigned geom[RayBatch::kMax], prim[RayBatch::kMax];
  const int traced = IntersectBatch(b, geom, prim);
  // Runs of consecutive lanes on the sky, or on one rectangle, are evaluated together (vectorised); hits with a
  // noise texture in short runs (or runs with lanes that see the back) are collected per rectangle and evaluated
  // together.
  constexpr int kShortNoiseRun = 16;
  int deferred[RayBatch::kMax], n_deferred = 0;
  const auto put = [&](int i, const Rgb& c) { rgb[3 * i] = c[0], rgb[3 * i + 1] = c[1], rgb[3 * i + 2] = c[2]; };
  RectPlaneRuns<T> planes;
  const T *s_at = planes.s, *t_at = planes.t, *denom = planes.denom;
  RunBreaks runs;
  FindRunBreaks(n, b.valid, geom, prim, runs.brk);
  for (int i = 0; i < n;) {
    const unsigned g = geom[i];
    if (!b.valid[i]) {
      put(i++, {0, 0, 0});
      continue;
    }
    // The run of lanes like lane i (valid, the same geometry and primitive; misses and the lanes of an analytic
    // shape have primitive 0).
    const int j = RunEnd(runs, i);
    if (g == RTC_INVALID_GEOMETRY_ID) {
      SkyColours(j - i, b.dz + i, desc_.sky.horizon.data(), desc_.sky.zenith.data(), desc_.sky.nadir.data(), rgb + 3 * i);
    } else if (g == rect_geom_) {
      const unsigned p = prim[i];
      const RectFrame& fr = rect_frames_[p];
      const T* flat;
      if constexpr (std::is_same_v<T, float>) flat = fr.flat_f; else flat = fr.flat;
      RectPlaneHits<T>(i, j - i, b.ox, b.oy, b.oz, b.dx, b.dy, b.dz, flat, &planes);
      const Rect& r = desc_.rects[p];
      const bool noise = r.front.kind == Texture::Kind::kNoise, double_sided = r.double_sided;
      // Edge-on: no hit (as Shade); the back of a single-sided rectangle: its back colour.
      // (In integers, without branches: the count below vectorises.)
      const int ds = double_sided ? 1 : 0;
      const auto seen = [&](int k) {
        const int nonzero = denom[k] != 0 ? 1 : 0, not_facing_away = denom[k] > 0 ? 0 : 1;
        return nonzero & (not_facing_away | ds);
      };
      int front = 0;
      for (int k = i; k < j; ++k) front += seen(k);
      if (front == j - i && (!noise || j - i >= kShortNoiseRun)) {
        r.front.EvalInto(j - i, s_at + i, t_at + i, rgb + 3 * i);
      } else if (noise) {
        int nd = n_deferred;
        for (int k = i; k < j; ++k) {   // without branches: the lane is kept when seen
          const int keep = seen(k);
          deferred[nd] = k, nd += keep;
        }
        n_deferred = nd;
      } else {
        for (int k = i; k < j; ++k)
          if (seen(k)) put(k, r.front.Eval(s_at[k], t_at[k]));
      }
      if (front < j - i)
        for (int k = i; k < j; ++k)
          if (!seen(k)) put(k, denom[k] == 0 ? Rgb{0, 0, 0} : r.back);
    } else if (g < geom_to_user_.size() && geom_to_user_[g] >= 0) {
      // A run of lanes on one analytic shape (the mount ring past the rim: long runs): one flat colour.
      const UserGeometry& u = *user_[geom_to_user_[g]];
      const Rgb& c = u.kind == UserGeometry::Kind::kMirror ? u.back_colour : u.colour;
      FillColour(j - i, c, rgb + 3 * i);
    } else {
      for (int k = i; k < j; ++k) put(k, {0, 0, 0});
    }
    i = j;
  }
  // The noise: one batch per rectangle, in order of first appearance (usually one: the floor). Each pass takes
  // the rays of the first rectangle left and keeps the others, in order, for the next.
  T s_batch[RayBatch::kMax], t_batch[RayBatch::kMax];
  int lanes[RayBatch::kMax];
  float colours[3 * RayBatch::kMax];
  for (int left = n_deferred; left > 0;) {
    const unsigned p = prim[deferred[0]];
    int m = 0, kept = 0;
    for (int k = 0; k < left; ++k) {
      const int i = deferred[k];
      if (prim[i] == p) {
        lanes[m] = i, s_batch[m] = s_at[i], t_batch[m] = t_at[i], ++m;
      } else {
        deferred[kept++] = i;
      }
    }
    desc_.rects[p].front.EvalInto(m, s_batch, t_batch, colours);
    for (int k = 0; k < m; ++k) put(lanes[k], {colours[3 * k], colours[3 * k + 1], colours[3 * k + 2]});
    left = kept;
  }
  return traced;
}

namespace {

// Lanes [i0, i1) of a run on one rectangle into the hits, from their plane points (RectPlaneHits): a hit unless
// the ray is parallel to the plane (denom 0), with the normal facing the ray (as Shade).
HOVS_VECTOR_CLONES
void RectHitLanes(int i0, int i1, const RectPlaneRuns<double>* __restrict planes, const double* __restrict normal, int id,
                  HitBatch* __restrict H) {
  const double n0 = normal[0], n1 = normal[1], n2 = normal[2];
  for (int k = i0; k < i1; ++k) {
    const bool hit = planes->denom[k] != 0;
    const double s = planes->denom[k] < 0 ? 1.0 : -1.0;
    H->hit[k] = hit ? 1 : 0;
    H->object_id[k] = hit ? id : static_cast<int>(kSkyId);
    // (Selects, not products: a ray parallel to the plane has an infinite distance and no finite point.)
    H->px[k] = hit ? planes->px[k] : 0.0, H->py[k] = hit ? planes->py[k] : 0.0, H->pz[k] = hit ? planes->pz[k] : 0.0;
    H->nx[k] = hit ? s * n0 : 0.0, H->ny[k] = hit ? s * n1 : 0.0, H->nz[k] = hit ? s * n2 : 0.0;
  }
}

// Lanes [i0, i1) of straight camera rays ending on their mount ring at distance t[k] (the renderer's analytic
// test): the point o + t d and the ring's normal n facing the ray (as UserHit).
HOVS_VECTOR_CLONES
void RingHitLanes(int i0, int i1, const double* __restrict ox, const double* __restrict oy,
                  const double* __restrict oz, const double* __restrict dx, const double* __restrict dy,
                  const double* __restrict dz, const double* __restrict t, const double* __restrict normal, int id,
                  HitBatch* __restrict H) {
  const double n0 = normal[0], n1 = normal[1], n2 = normal[2];
  for (int k = i0; k < i1; ++k) {
    const double s = dx[k] * n0 + dy[k] * n1 + dz[k] * n2 < 0 ? 1.0 : -1.0;
    H->hit[k] = 1;
    H->object_id[k] = id;
    H->px[k] = ox[k] + t[k] * dx[k], H->py[k] = oy[k] + t[k] * dy[k], H->pz[k] = oz[k] + t[k] * dz[k];
    H->nx[k] = s * n0, H->ny[k] = s * n1, H->nz[k] = s * n2;
  }
}

}  // namespace

int RayScene::Geometry(const RayBatch& b, HitBatch* H) const {
  unsigned geom[RayBatch::kMax], prim[RayBatch::kMax];
  const int traced = IntersectBatch(b, geom, prim);
  RectPlaneRuns<double> planes;
  // Lane k ends on its unit's mount ring at the renderer's analytic distance: the unit, else -1.
  const auto ring_unit = [&](int k) {
    const int u = b.from_camera[k];
    return b.valid[k] && u >= 0 && static_cast<size_t>(u) < own_mount_.size() && own_mount_[u].geometry &&
                   b.mount_t[k] > 0 && geom[k] == own_mount_[u].geom_id
               ? u
               : -1;
  };
  RunBreaks runs;
  FindRunBreaks(b.n, b.valid, geom, prim, runs.brk);
  for (int i = 0; i < b.n;) {
    int j = i + 1;
    if (b.valid[i] && geom[i] == rect_geom_) {
      // A run of consecutive lanes on one rectangle: their plane points in one vectorised pass (as Shade).
      const unsigned p = prim[i];
      j = RunEnd(runs, i);
      const RectFrame& fr = rect_frames_[p];
      RectPlaneHits<double>(i, j - i, b.ox, b.oy, b.oz, b.dx, b.dy, b.dz, fr.flat, &planes);
      RectHitLanes(i, j, &planes, fr.normal.data(), desc_.rects[p].object_id, H);
      i = j;
      continue;
    }
    if (const int u = ring_unit(i); u >= 0) {
      // A run of straight camera rays that ended on their own mount ring: the ring's distance is already known
      // (in double); Shade would solve it again. The ring's normal is its local z.
      // Usually the whole run of lanes on the ring geometry is the camera's straight rays: tested in one pass
      // over the run, else lane by lane.
      const int e = RunEnd(runs, i);
      int straight = 0;
      for (int k = i; k < e; ++k) straight += (b.from_camera[k] == u ? 1 : 0) & (b.mount_t[k] > 0 ? 1 : 0);
      if (straight == e - i) {
        j = e;
      } else {
        while (j < b.n && ring_unit(j) == u) ++j;
      }
      const UserGeometry& g = *own_mount_[u].geometry;
      const Vec3d n = g.R_world_from_local.col(2);
      RingHitLanes(i, j, b.ox, b.oy, b.oz, b.dx, b.dy, b.dz, b.mount_t, n.data(), g.object_id, H);
      i = j;
      continue;
    }
    Hit h;
    if (b.valid[i] && geom[i] != RTC_INVALID_GEOMETRY_ID)
      Shade(Vec3d(b.ox[i], b.oy[i], b.oz[i]), Vec3d(b.dx[i], b.dy[i], b.dz[i]), geom[i], prim[i], &h, false);
    H->hit[i] = h.hit ? 1 : 0;
    H->object_id[i] = h.object_id;
    H->px[i] = h.point.x(), H->py[i] = h.point.y(), H->pz[i] = h.point.z();
    H->nx[i] = h.normal.x(), H->ny[i] = h.normal.y(), H->nz[i] = h.normal.z();
    i = j;
  }
  return traced;
}

Hit RayScene::Trace(const Vec3d& origin, const Vec3d& direction, double tnear, int from_mirror) const {
  Hit h;
  Trace16(1, &origin, &direction, &tnear, &h, &from_mirror);
  return h;
}

bool RayScene::Occluded(const Vec3d& a, const Vec3d& b, double eps) const {
  const Vec3d seg = b - a;
  const double len = seg.norm();
  if (len <= 2 * eps) return false;
  const Vec3d d = seg / len;
  RTCRay ray;
  ray.org_x = static_cast<float>(a.x()), ray.org_y = static_cast<float>(a.y()), ray.org_z = static_cast<float>(a.z());
  ray.dir_x = static_cast<float>(d.x()), ray.dir_y = static_cast<float>(d.y()), ray.dir_z = static_cast<float>(d.z());
  ray.tnear = static_cast<float>(eps);
  ray.tfar = static_cast<float>(len - eps);
  ray.mask = 0xFFFFFFFFu;
  ray.flags = 0;
  ray.time = 0;
  ray.id = 0;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  rtcOccluded1(scene_, &ctx, &ray);
  return ray.tfar < 0;
}

void RayScene::IntersectOnly16(int count, const Vec3d* o, const Vec3d* d, unsigned* geom_ids,
                               const int* from_mirror) const {
  alignas(64) RTCRayHit16 rh;
  IntersectPacket(scene_, count, o, d, nullptr, from_mirror, &rh);
  if (!instances_.empty()) MapInstanceHits(count, rh.hit.instID[0], rh.hit.geomID, rh.hit.primID);
  for (int i = 0; i < count; ++i) geom_ids[i] = rh.hit.geomID[i];
}

namespace {
// Lanes [i0, i0 + W) of a raw packet into an Embree packet of width W, every lane valid. (SetLane's fields with
// the mask and id computed once: with SetLane per lane the raw figure was about 6 % slower.)
template <int W, class RayHitW>
void FillRawPacket(const RayScene::RawPacket16& p, int i0, unsigned mask, unsigned id, int* valid, RayHitW* rh) {
  for (int i = 0; i < W; ++i) {
    valid[i] = -1;
    rh->ray.org_x[i] = p.ox[i0 + i], rh->ray.org_y[i] = p.oy[i0 + i], rh->ray.org_z[i] = p.oz[i0 + i];
    rh->ray.dir_x[i] = p.dx[i0 + i], rh->ray.dir_y[i] = p.dy[i0 + i], rh->ray.dir_z[i] = p.dz[i0 + i];
    rh->ray.tnear[i] = 0, rh->ray.tfar[i] = std::numeric_limits<float>::infinity();
    rh->ray.mask[i] = mask, rh->ray.id[i] = id, rh->ray.flags[i] = 0, rh->ray.time[i] = 0;
    rh->hit.geomID[i] = RTC_INVALID_GEOMETRY_ID, rh->hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
  }
}
}  // namespace

void RayScene::IntersectRaw(const RawPacket16& p, int from_mirror, int width, unsigned* geom_ids) const {
  const unsigned mask = RayMask(from_mirror), id = static_cast<unsigned>(std::max(from_mirror, -1) + 1);
  if (width == 16) {
    alignas(64) RTCRayHit16 rh;
    alignas(64) int valid[16];
    FillRawPacket<16>(p, 0, mask, id, valid, &rh);
    TracePacket(scene_, valid, &rh, rtcIntersect16);
    for (int i = 0; i < 16; ++i) geom_ids[i] = rh.hit.geomID[i];
    return;
  }
  HOVS_REQUIRE(width == 8, "IntersectRaw", "width must be 8 or 16 (got ", width, ")");
  for (int i0 = 0; i0 < 16; i0 += 8) {
    alignas(32) RTCRayHit8 rh;
    alignas(32) int valid[8];
    FillRawPacket<8>(p, i0, mask, id, valid, &rh);
    TracePacket(scene_, valid, &rh, rtcIntersect8);
    for (int i = 0; i < 8; ++i) geom_ids[i0 + i] = rh.hit.geomID[i];
  }
}

}  // namespace hovs::raytrace
