#include <cmath>
#include <limits>

#include "raytrace/scene_internal.h"

namespace hovs::raytrace::internal {

using UG = RayScene::UserGeometry;

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

}  // namespace hovs::raytrace::internal
