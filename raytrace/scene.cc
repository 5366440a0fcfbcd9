#include "raytrace/scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "core/error.h"
#include "core/vector_clones.h"
#include "raytrace/scene_internal.h"

namespace hovs::raytrace {
using namespace internal;

Rgb Sky::Eval(const Vec3d& d) const {
  const double z = std::clamp(d.z(), -1.0, 1.0);
  const auto mix = [](const Rgb& a, const Rgb& b, double t) {
    const float f = static_cast<float>(t);
    return Rgb{a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])};
  };
  return z >= 0 ? mix(horizon, zenith, std::sqrt(z)) : mix(horizon, nadir, std::sqrt(-z));
}

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
      HOVS_REQUIRE(inside(r.world_from_rect * corner), "scene object " + name_of(r.object_id), "reaches beyond ",
                   kWorldExtent,
                   " m from the world origin along an axis: the renderer traces in "
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
  HOVS_REQUIRE(device_ != nullptr, "embree", "cannot create a device (error ",
               static_cast<int>(rtcGetDeviceError(nullptr)), ")");
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
  for (size_t ui = 0; ui < desc_.units.size(); ++ui) moving[ui] = desc_.units[ui].Moves();
  size_t world_rects = 0;
  const std::vector<std::pair<size_t, size_t>> body_rects = AddCameraBodies(moving, &world_rects);
  MakeRectFrames();
  // All rectangles of the world: one quad mesh; primID = index into rects.
  if (world_rects > 0) rect_geom_ = AttachQuads(scene_, 0, world_rects, nullptr);
  // The time Embree's ray time [0, 1] spans (AttachMovingUnit): kMaxExposureTime, shorter when a unit turns so fast
  // that its instance would need more time steps than Embree takes.
  for (size_t ui = 0; ui < desc_.units.size(); ++ui) {
    const double rate = desc_.units[ui].angular_velocity.norm();
    if (moving[ui] && rate > 0)
      motion_horizon_ = std::min(motion_horizon_, kMaxMotionSegments * kMotionSegmentAngle / rate);
  }
  unsigned next_id = rect_geom_ == RTC_INVALID_GEOMETRY_ID ? 0u : rect_geom_ + 1;  // past the world's ids
  for (size_t ui = 0; ui < desc_.units.size(); ++ui) AddUnitParts(ui, moving[ui] != 0, body_rects[ui], &next_id);
  rtcCommitScene(scene_);
  NumberInstanceShapes(next_id);
  DecideMountPaths(body_rects);
}

std::vector<std::pair<size_t, size_t>> RayScene::AddCameraBodies(const std::vector<char>& moving, size_t* world_rects) {
  // A box behind each unit's lens face, along the optical axis: the still units' first, then the moving units'
  // (which go into their instances, not into the world's quad mesh).
  std::vector<std::pair<size_t, size_t>> body_rects(desc_.units.size());
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
    if (pass == 0) *world_rects = desc_.rects.size();
  }
  return body_rects;
}

void RayScene::MakeRectFrames() {
  for (const Rect& r : desc_.rects) {
    const Eigen::Matrix3d R = r.world_from_rect.rotation.toRotationMatrix();
    RectFrame fr{r.world_from_rect.translation, R.col(2), R.col(0), R.col(1), {}, {}};
    for (int c = 0; c < 3; ++c)
      fr.flat[c] = fr.centre(c), fr.flat[3 + c] = fr.normal(c), fr.flat[6 + c] = fr.axis_x(c),
      fr.flat[9 + c] = fr.axis_y(c);
    for (int c = 0; c < 12; ++c) fr.flat_f[c] = static_cast<float>(fr.flat[c]);
    rect_frames_.push_back(fr);
  }
}

unsigned RayScene::AttachQuads(RTCScene target, size_t first, size_t last, const Rigid3d* frame_from_world) {
  RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_QUAD);
  const size_t count = last - first;
  auto* v = static_cast<float*>(
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 4 * count));
  auto* idx = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 4 * sizeof(unsigned), count));
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
}

std::pair<int, unsigned> RayScene::AttachShape(std::unique_ptr<UserGeometry> ug, RTCScene target, bool instanced) {
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
}

void RayScene::RecordShape(int slot, unsigned id) {
  const UserGeometry& ug = *user_[slot];
  if (ug.kind == UserGeometry::Kind::kAnnulus && ug.object_id == kMountId && ug.unit >= 0 && ug.unit < kMaskUnits) {
    if (own_mount_.size() <= static_cast<size_t>(ug.unit)) own_mount_.resize(ug.unit + 1);
    own_mount_[ug.unit] = {&ug, id};
  }
  if (geom_to_user_.size() <= id) geom_to_user_.resize(id + 1, -1);
  geom_to_user_[id] = slot;
}

namespace {

// A unit's analytic shapes at time 0: its mirror, its mount ring (the annulus from the rim out to
// mount_outer_radius in the rim plane) and its lens face (a disc at the camera centre).
std::array<std::unique_ptr<RayScene::UserGeometry>, 3> UnitShapes(const CatadioptricUnit& u, int ui) {
  using UG = RayScene::UserGeometry;
  auto mirror = std::make_unique<UG>();
  mirror->kind = UG::Kind::kMirror;
  mirror->object_id = kMirrorId;
  mirror->unit = ui;
  mirror->mirror = u.rig.mirror;
  mirror->world_from_local = u.world_from_mirror;
  mirror->local_from_world = u.world_from_mirror.Inverse();
  mirror->back_colour = u.mirror_back_colour;
  auto mount = std::make_unique<UG>();
  mount->kind = UG::Kind::kAnnulus;
  mount->object_id = kMountId;
  mount->unit = ui;
  mount->r_inner = u.rig.mirror.RimRadius();
  mount->r_outer = u.mount_outer_radius;
  mount->world_from_local = u.world_from_mirror * Rigid3d::Translation(Vec3d(0, 0, u.rig.mirror.RimZ()));
  mount->local_from_world = mount->world_from_local.Inverse();
  mount->colour = mount->back_colour = u.mount_colour;
  auto lens = std::make_unique<UG>();
  lens->kind = UG::Kind::kAnnulus;
  lens->object_id = kCameraBodyId;
  lens->unit = ui;
  lens->r_inner = 0;
  lens->r_outer = u.rig.occluder_radius;
  lens->world_from_local = u.world_from_mirror * u.rig.cam_from_mirror.Inverse();
  lens->local_from_world = lens->world_from_local.Inverse();
  lens->colour = lens->back_colour = u.body_colour;
  return {std::move(mirror), std::move(mount), std::move(lens)};
}

}  // namespace

void RayScene::AddUnitParts(size_t ui, bool instanced, const std::pair<size_t, size_t>& body, unsigned* next_id) {
  CatadioptricUnit& u = desc_.units[ui];
  if (u.mount_outer_radius <= 0) u.mount_outer_radius = DefaultMountRadius(u);
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
    mi.rect_base = static_cast<unsigned>(body.first);
    mi.quad_geom = AttachQuads(target, body.first, body.second, &mirror_from_world);
  }
  auto shapes = UnitShapes(u, static_cast<int>(ui));
  for (size_t k = 0; k < shapes.size(); ++k) {  // mirror, mount ring, lens face
    if (instanced) shapes[k]->ray_from_local = mirror_from_world * shapes[k]->world_from_local;
    const auto [slot, id] = AttachShape(std::move(shapes[k]), target, instanced);
    if (!instanced) {
      RecordShape(slot, id);
      *next_id = std::max(*next_id, id + 1);
      continue;
    }
    if (mi.geom.size() <= id) mi.geom.resize(id + 1, RTC_INVALID_GEOMETRY_ID);
    mi.geom[id] = static_cast<unsigned>(slot);  // a slot for now; the scene-wide id in NumberInstanceShapes
    if (k == 1) mi.mount_inner = id;
    if (k == 2) mi.lens_inner = id;
  }
  if (!instanced) return;
  rtcCommitScene(target);
  DescribeOwnParts(u, ui < static_cast<size_t>(kMaskUnits), mirror_from_world, &mi.own);
  const unsigned inst = AttachMovingUnit(u, target, mi.own.mask);
  rtcReleaseScene(target);  // the instance holds it
  if (unit_instance_.size() <= ui) unit_instance_.resize(ui + 1, -1);
  unit_instance_[ui] = static_cast<int>(instances_.size());
  *next_id = std::max(*next_id, inst + 1);
  if (inst_slot_.size() <= inst) inst_slot_.resize(inst + 1, -1);
  inst_slot_[inst] = static_cast<int>(instances_.size());
  instances_.push_back(std::move(mi));
}

void RayScene::DescribeOwnParts(const CatadioptricUnit& u, bool analytic, const Rigid3d& mirror_from_world,
                                OwnPartShapes* own) {
  const int ui = static_cast<int>(&u - desc_.units.data());
  own->analytic = analytic;
  own->mask = analytic ? LensMaskBit(ui) | MountMaskBit(ui) : 0xFFFFFFFFu;
  const Eigen::Matrix3d Rc = u.rig.cam_from_mirror.rotation.toRotationMatrix();
  const Eigen::Matrix3d Rw = mirror_from_world.rotation.toRotationMatrix();
  for (int k = 0; k < 9; ++k) own->shape[k] = Rc.data()[k], own->R_mirror_from_world[k] = Rw.data()[k];
  for (int k = 0; k < 3; ++k)
    own->shape[9 + k] = u.rig.cam_from_mirror.translation(k),
                   own->t_mirror_from_world[k] = mirror_from_world.translation(k);
  own->shape[12] = u.rig.occluder_radius * u.rig.occluder_radius;
  own->shape[13] = u.rig.mirror.RimZ();
  own->shape[14] = u.rig.mirror.RimRadius() * u.rig.mirror.RimRadius();
  own->shape[15] = u.mount_outer_radius * u.mount_outer_radius;
  own->shape[16] = BodyHalfWidth(u), own->shape[17] = u.body_length;
}

void RayScene::NumberInstanceShapes(unsigned next_id) {
  // The moving units' shapes get scene-wide ids past the world's (hits in their instances are mapped to them:
  // MapInstanceHits), and their camera bodies' rectangles the world's quad id (there may be no world quads).
  if (!instances_.empty() && rect_geom_ == RTC_INVALID_GEOMETRY_ID) rect_geom_ = next_id++;
  for (MotionInstance& mi : instances_) {
    for (unsigned& g : mi.geom) {
      if (g == RTC_INVALID_GEOMETRY_ID) continue;
      const unsigned id = next_id++;
      RecordShape(static_cast<int>(g), id);
      g = id;
    }
    mi.own.lens_geom = mi.geom[mi.lens_inner], mi.own.mount_geom = mi.geom[mi.mount_inner];
  }
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
    if (step > 0 && q.dot(previous) < 0) q.coeffs() *= -1;  // the short way round between steps
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
    if (slot < 0) {  // (no other instances exist)
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
  for (int k = 0; k < 4; ++k)
    corners.push_back(m.geometry->world_from_local * Vec3d((k & 1) ? r : -r, (k & 2) ? r : -r, 0));
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
    for (int k = 0; k < 8; ++k)
      points.push_back(mirror_from_world * at_zero.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k)));
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
}  // namespace hovs::raytrace
