// The renderer's world: textured rectangles (boards, walls, boxes, the ground), catadioptric units (the exact
// mirror of core/ as Embree user geometry with analytic double-precision intersection and normals, the
// mirror's mount ring, the camera's lens face and body as occluders), and a sky. World frame: z up, metres.
#pragma once

#include <embree3/rtcore.h>

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/catadioptric.h"
#include "core/lens.h"
#include "core/rigid.h"
#include "raytrace/texture.h"

namespace hovs::raytrace {

// How far from the world origin (m, along each axis) a scene may reach: Embree traces in single precision,
// whose spacing there is about 1 mm. RayScene rejects a scene that reaches further (or is not finite).
constexpr double kWorldExtent = 1e4;
// The largest thin-lens aperture radius (m) the renderer takes (RenderOptions::lens_radius): straight camera rays
// may leave any point within it of a unit's camera centre (RayScene::OwnMount::path_clear allows for that).
constexpr double kMaxApertureRadius = 0.1;
// The longest exposure the renderer takes (RenderOptions::exposure_time), s. A scene whose units turn faster than
// about 20 rad/s covers less (RayScene::MotionHorizon).
constexpr double kMaxExposureTime = 10;

// Object ids written to the ground truth. Scene objects number from kFirstObjectId in the order given.
enum ObjectId : int { kSkyId = 0, kMountId = 1, kCameraBodyId = 2, kMirrorId = 3, kFirstObjectId = 4 };

// A rectangle: centred at world_from_rect's origin, spanning x in [-w/2, w/2], y in [-h/2, h/2]; its front
// face looks along +z of its frame. Texture coordinates (s, t) are (x, y) in metres.
struct Rect {
  int object_id = kFirstObjectId;
  Rigid3d world_from_rect;
  double width = 1, height = 1;
  Texture front;
  Rgb back = {0.55f, 0.55f, 0.57f};  // aluminium
  bool double_sided = false;         // back shows the front texture mirrored
};

struct CatadioptricUnit {
  std::string name = "unit0";
  CatadioptricCamera<double> rig;  // mirror-frame model: mirror, camera, cam_from_mirror, occluder radius
  // The camera's lens (core/lens.h): its aperture and focus defocus the unit's images, and rig.camera's image
  // scale is its sensor distance at that focus. None: an ideal pinhole (unless RenderOptions::lens_radius > 0).
  std::optional<ThinLens> lens;
  Rigid3d world_from_mirror;               // places the viewpoint F1 in the world
  double mount_outer_radius = 0;           // the mount ring around the rim (0: rim diameter / 2 + 15 mm)
  double body_length = 0.12;               // camera body behind the lens face
  Vec3d velocity = Vec3d::Zero();          // m/s, world frame (motion blur)
  Vec3d angular_velocity = Vec3d::Zero();  // rad/s, world frame, about the viewpoint (motion blur)
  bool Moves() const { return velocity != Vec3d::Zero() || angular_velocity != Vec3d::Zero(); }
  // The unit's pose at time tau after the start of the exposure.
  Rigid3d WorldFromMirrorAt(double tau) const {
    if (tau == 0) return world_from_mirror;
    return Rigid3d(QuaternionFromAngleAxis<double>(Vec3d(angular_velocity * tau)) * world_from_mirror.rotation,
                   world_from_mirror.translation + velocity * tau);
  }
  Rgb mount_colour = {0.03f, 0.03f, 0.035f};
  Rgb body_colour = {0.08f, 0.08f, 0.09f};
  Rgb mirror_back_colour = {0.25f, 0.25f, 0.27f};
};

struct Sky {
  Rgb zenith = {0.35f, 0.55f, 0.9f};
  Rgb horizon = {0.85f, 0.9f, 0.95f};
  Rgb nadir = {0.3f, 0.28f, 0.25f};
  Rgb Eval(const Vec3d& direction_world) const;
};

// The six outward-facing rectangles of a box of `size` (x, y, z) whose bottom face is centred at
// world_from_base's origin.
std::vector<Rect> MakeBox(const Rigid3d& world_from_base, const Vec3d& size, const Texture& texture, int object_id,
                          bool double_sided = false);

struct SceneObjectInfo {
  int id;
  std::string name, type;
};

struct SceneDescription {
  std::vector<Rect> rects;
  std::vector<CatadioptricUnit> units;
  std::vector<SceneObjectInfo> objects;  // id -> name, for the ground truth
  Sky sky;
};

// A hit of a double-precision ray, shaded.
struct Hit {
  bool hit = false;
  int object_id = kSkyId;
  double t = 0;  // along the ray (unit direction)
  Vec3d point = Vec3d::Zero();
  Vec3d normal = Vec3d::Zero();  // world, facing the ray
  Rgb colour = {0, 0, 0};
  int unit = -1;  // for mirror / mount / body hits: which unit
};

// Rays in structure-of-arrays form: the renderer's per-sample path, traced 16 at a time. T = double: the
// ground-truth rays and the general path (thin lens, motion blur, lens distortion, pinhole views); T = float
// (RayBatchF): the colour samples of a unit's undistorted camera, made and shaded in single precision, which
// Embree traces in anyway.
template <class T>
struct RayBatchOf {
  static constexpr int kMax = 256;
  int n = 0;
  alignas(64) T ox[kMax], oy[kMax], oz[kMax];  // world
  alignas(64) T dx[kMax], dy[kMax], dz[kMax];  // world, unit
  alignas(64) float tnear[kMax];
  alignas(64) int from_mirror[kMax];  // the unit whose mirror the ray leaves, -1: none
  alignas(64) int from_camera[kMax];  // the unit whose camera it leaves past the mirror, -1: none
  // For rays with from_camera >= 0: where the ray meets that unit's mount ring (t along d), 0 if it does not,
  // < 0 if not computed (RayScene then computes it).
  alignas(64) T mount_t[kMax];
  alignas(64) unsigned char valid[kMax];  // 0: no ray (outside the camera's domain): black, no hit
  // Motion blur: each ray's time in the exposure (s), where timed; else every ray is at time 0. Moving units'
  // parts are met where they are at that time.
  bool timed = false;
  alignas(64) float time[kMax];
  // Where mirror_frame is set: the rays leaving a unit's mirror (from_mirror) in that unit's mirror frame, origin
  // and direction (the thin-lens and motion-blur rays, whose world rays are each at its own time). RayScene meets
  // a moving unit's own parts there; without them it maps the world rays back at time 0.
  bool mirror_frame = false;
  alignas(64) T mox[kMax], moy[kMax], moz[kMax], mdx[kMax], mdy[kMax], mdz[kMax];
  // false: something may come between a unit's camera and its mount ring during the exposure (a moving unit:
  // RayScene::MountPathClearDuring), so the straight camera rays of the batch go to Embree up to the ring even
  // where RayScene::MountPathClear (which looks at time 0) says nothing is in between.
  bool mount_paths_clear = true;
};
using RayBatch = RayBatchOf<double>;
using RayBatchF = RayBatchOf<float>;

// The hits of a batch without colour, in structure-of-arrays form (the ground-truth path): lane i as Hit's
// hit, object_id, point and normal. Where hit[i] = 0 (no ray, or nothing met): object_id kSkyId, point and
// normal zero.
struct HitBatch {
  alignas(64) double px[RayBatch::kMax], py[RayBatch::kMax], pz[RayBatch::kMax];  // world
  alignas(64) double nx[RayBatch::kMax], ny[RayBatch::kMax], nz[RayBatch::kMax];  // world, facing the ray
  alignas(64) int object_id[RayBatch::kMax];
  alignas(64) unsigned char hit[RayBatch::kMax];
};

struct BatchLanes;  // a batch's Embree lanes (scene.cc)

// The Embree scene built from a description. Thread-safe for tracing once built.
class RayScene {
 public:
  explicit RayScene(SceneDescription description);
  ~RayScene();
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  const SceneDescription& description() const { return desc_; }

  // Traces up to 16 rays as one packet (rtcIntersect16). Directions must be unit vectors. Hits are
  // recomputed in double on the analytic surface that Embree found, then shaded. from_mirror (optional): per
  // ray, the unit whose mirror it leaves (-1: none), which it cannot hit again (the mirror is convex).
  // colour = false: geometry only (point, normal, id; no texture lookup), for ground-truth rays.
  void Trace16(int count, const Vec3d* origins, const Vec3d* directions, const double* tnear, Hit* hits,
               const int* from_mirror = nullptr, bool colour = true) const;
  // The colour seen along each ray of a batch (3 floats per ray; black where !valid): Trace16 with colour,
  // without the hit geometry, and with the textures evaluated in batches. Returns how many of the batch's rays
  // went to Embree (the others ended analytically: a unit's camera rays past the rim on its mount ring when
  // nothing can lie in between, invalid lanes).
  int Colours(const RayBatch& batch, float* rgb) const;
  // The same for single-precision rays: the plane hits and texture coordinates in float too.
  int Colours(const RayBatchF& batch, float* rgb) const;
  // The hits of a batch without colour (point, normal, id): the ground-truth path. The same values as Trace16
  // without colour, lane by lane; runs of lanes on one rectangle or on their unit's mount ring are evaluated
  // together (vectorised).
  // Returns how many of the batch's rays went to Embree, as Colours.
  int Geometry(const RayBatch& batch, HitBatch* hits) const;
  Hit Trace(const Vec3d& origin, const Vec3d& direction, double tnear = 0, int from_mirror = -1) const;
  // True if anything blocks the open segment from a to b (rtcOccluded1).
  bool Occluded(const Vec3d& a, const Vec3d& b, double eps = 1e-7) const;

  // rtcIntersect16 only, no shading, each lane filled from doubles (the benchmark's raw reference until measurement
  // 22; IntersectRaw below is the reference now).
  void IntersectOnly16(int count, const Vec3d* origins, const Vec3d* directions, unsigned* geom_ids,
                       const int* from_mirror = nullptr) const;
  // Sixteen rays already in single precision, structure of arrays (the layout of Embree's packets), all leaving
  // one unit's mirror (from_mirror >= 0) or none (-1), tnear 0: copied into the packet with vector moves and
  // traced with rtcIntersect16 (width 16) or two rtcIntersect8 (width 8); geometry ids only. The raw reference
  // with the least work a caller must do per ray (IntersectOnly16 converts each lane from double, which takes
  // about as long as Embree's traversal of these rays).
  struct RawPacket16 {
    alignas(64) float ox[16], oy[16], oz[16], dx[16], dy[16], dz[16];
  };
  // (Ids as Embree gives them: a moving unit's parts have their ids inside its instance.)
  void IntersectRaw(const RawPacket16& packet, int from_mirror, int width, unsigned* geom_ids) const;

  struct UserGeometry;  // mirror, annulus (mount, lens face): analytic shapes, defined in scene.cc
  // A unit's mount ring, met analytically by that unit's straight camera rays (IntersectBatch).
  // When nothing but the unit's own parts lies between its camera centre (or any point of a thin-lens aperture
  // around it, kMaxApertureRadius) and its mount ring (path_clear, decided once from bounding boxes at time 0),
  // those rays end on the ring without going to Embree at all. A motion-blurred frame also needs the boxes swept
  // over its exposure clear (MountPathClearDuring; RayBatch::mount_paths_clear).
  struct OwnMount {
    const UserGeometry* geometry = nullptr;
    unsigned geom_id = 0;
    bool path_clear = false;
  };
  // True if unit's straight camera rays (from its camera centre, past the rim) are known to meet nothing
  // before its mount ring, so they skip Embree (see OwnMount).
  bool MountPathClear(int unit) const;
  // MountPathClear over the whole exposure [0, exposure] (s): nothing comes between the unit's camera centre (or
  // its aperture) and its mount ring while the units move (the unit itself, other units' parts, both at once).
  // The same as MountPathClear when no unit moves or exposure is 0.
  bool MountPathClearDuring(int unit, double exposure) const;
  // The longest exposure (s) over which the moving units' parts are where their motion puts them:
  // kMaxExposureTime unless a unit turns faster than about 20 rad/s (Embree takes at most 129 time steps).
  double MotionHorizon() const { return motion_horizon_; }
  // True when unit moves and the rays leaving its mirror or its camera meet its own parts (which move with it)
  // analytically in its mirror frame and skip its instance (which they would all enter: they start inside it).
  bool OwnPartsInMirrorFrame(int unit) const {
    return unit >= 0 && static_cast<size_t>(unit) < unit_instance_.size() && unit_instance_[unit] >= 0 &&
           instances_[unit_instance_[unit]].own.analytic;
  }

 private:
  void Shade(const Vec3d& o, const Vec3d& d, unsigned geom_id, unsigned prim_id, Hit* hit, bool colour) const;
  // A hit on analytic geometry g at distance t along o + t d, with g's normal n there (any side).
  static void UserHit(const UserGeometry& g, const Vec3d& o, const Vec3d& d, double t, const Vec3d& n, Hit* h);
  // Sets OwnMount::path_clear; body_rects: by unit, the range of desc_.rects holding its camera body.
  void DecideMountPaths(const std::vector<std::pair<size_t, size_t>>& body_rects);
  // Whether nothing but unit u's own parts comes near the region between its camera and its mount ring during
  // [0, exposure] (bounding boxes, swept along the units' motions).
  bool PathClearOver(size_t u, double exposure) const;
  // Intersects the rays of a batch: their Embree lanes set up once, then packets of 16 (rtcIntersect16) where
  // the CPU has native 16-wide packets, else of 8 (rtcIntersect8). Returns the number of rays given to Embree.
  template <class T>
  int IntersectBatch(const RayBatchOf<T>& b, unsigned* geom_ids, unsigned* prim_ids) const;
  template <class T>
  int ColoursOf(const RayBatchOf<T>& b, float* rgb) const;

  // A rectangle's frame for shading: centre, unit normal and in-plane axes in the world.
  struct RectFrame {
    Vec3d centre, normal, axis_x, axis_y;
    double flat[12];   // the four vectors in this order, as the vectorised plane hits take them
    float flat_f[12];  // the same rounded to float (single-precision rays)
  };
  std::vector<RectFrame> rect_frames_;

  SceneDescription desc_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  unsigned rect_geom_ = RTC_INVALID_GEOMETRY_ID;
  bool native16_ = false;                              // the device traces 16-wide packets natively (AVX-512)
  std::vector<std::unique_ptr<UserGeometry>> user_;    // index = user geometry slot
  std::vector<int> geom_to_user_;                      // geomID -> slot in user_, or -1
  std::vector<OwnMount> own_mount_;                    // by unit, for the units with their own Embree mask bits
  std::vector<std::pair<size_t, size_t>> body_rects_;  // by unit, the range of desc_.rects holding its camera body

  // A unit that moves (velocity or angular velocity not zero) has its parts (camera body rectangles, mirror, mount
  // ring, lens face) in a scene of its own, in its mirror frame, instanced in the world with its motion over
  // [0, motion_horizon_]. So under motion blur a ray at time tau meets them where they are then: the camera's
  // reflection stays sharp, as it moves with the mirror. Their hits are mapped to scene-wide ids (the world's
  // rectangles' id and the rectangle's index in desc_.rects; ids past the world's for the shapes), so that
  // shading and ground truth treat them as the still units' parts (at time 0).
  // The parts of a moving unit as its own rays meet them, in its mirror frame (OwnParts): the lens face (a disc
  // at the camera centre, in the camera frame), the mount ring (an annulus in the rim plane) and the camera body
  // (the box of its six rectangles, in the camera frame: x, y in [-half, half], z in [-length, 0]).
  struct OwnPartShapes {
    bool analytic = false;  // units 0-9 (their own mask bits); the others' rays enter the instance
    // As OwnPartLanes takes them: R_cam_from_mirror (9, column-major), t_cam_from_mirror (3), then the lens
    // face's radius squared, the rim plane's z, the rim's and the mount's outer radius squared, the body's half
    // width and length.
    double shape[18] = {};
    unsigned lens_geom = RTC_INVALID_GEOMETRY_ID, mount_geom = RTC_INVALID_GEOMETRY_ID;  // scene-wide ids
    unsigned mask = 0;  // the instance's mask (the unit's lens-face and mount bits): cleared for own rays
    double R_mirror_from_world[9] = {}, t_mirror_from_world[3] = {};  // time 0, column-major
  };
  struct MotionInstance {
    unsigned quad_geom = RTC_INVALID_GEOMETRY_ID;  // the camera body's quad mesh in the unit's scene
    unsigned rect_base = 0;                        // its first rectangle in desc_.rects
    std::vector<unsigned> geom;                    // the unit scene's geomID -> scene-wide id
    unsigned lens_inner = 0, mount_inner = 0;      // the lens face's and mount's ids in the unit's scene
    OwnPartShapes own;
  };
  static constexpr int kMaxMotionSegments = RTC_MAX_TIME_STEP_COUNT - 1;
  static constexpr double kMotionSegmentAngle = 1.5707963267948966;  // rad: a quarter turn per time step at most
  unsigned AttachMovingUnit(const CatadioptricUnit& unit, RTCScene unit_scene, unsigned mask);
  // The constructor's steps (scene.cc). The units' camera bodies as rectangles of desc_.rects, by unit its range
  // ([first, last)); *world_rects: where the still units' end (the moving units' go into their instances).
  std::vector<std::pair<size_t, size_t>> AddCameraBodies(const std::vector<char>& moving, size_t* world_rects);
  void MakeRectFrames();  // rect_frames_ from desc_.rects
  // Rectangles [first, last) as one quad mesh (primID = index - first), in the world or (frame_from_world given)
  // in that frame; its id in target.
  unsigned AttachQuads(RTCScene target, size_t first, size_t last, const Rigid3d* frame_from_world);
  // An analytic shape attached to target (the world, or a moving unit's scene: instanced); its slot in user_ and
  // its id in target.
  std::pair<int, unsigned> AttachShape(std::unique_ptr<UserGeometry> shape, RTCScene target, bool instanced);
  void RecordShape(int slot, unsigned id);  // registers a shape under its scene-wide id
  // A unit's mirror, mount ring and lens face, in the world (or, moving, in an instance of their own with its
  // camera body's rectangles body); *next_id: past every id used so far.
  void AddUnitParts(size_t unit, bool moving, const std::pair<size_t, size_t>& body, unsigned* next_id);
  void DescribeOwnParts(const CatadioptricUnit& unit, bool analytic, const Rigid3d& mirror_from_world,
                        OwnPartShapes* own);
  // Scene-wide ids for the moving units' shapes, from next_id on.
  void NumberInstanceShapes(unsigned next_id);
  // A batch's own rays of unit U (from its mirror or its camera) meet U's parts in its mirror frame: where one does,
  // the world trace looks only nearer (lanes->tfar) and own_geom / own_prim take over if it finds nothing; all
  // skip U's instance (lanes->mask_off). Returns whether any lane met a part.
  template <class T>
  bool OwnParts(const RayBatchOf<T>& b, int U, BatchLanes* lanes, unsigned* own_geom, unsigned* own_prim) const;
  // Hits found inside an instance (inst[i] valid) to scene-wide ids (geom, prim).
  void MapInstanceHits(int n, const unsigned* inst, unsigned* geom, unsigned* prim) const;
  std::vector<MotionInstance> instances_;
  std::vector<int> inst_slot_;      // world geomID of an instance -> index in instances_, or -1
  std::vector<int> unit_instance_;  // unit -> index in instances_, or -1
  double motion_horizon_ = kMaxExposureTime;
};

}  // namespace hovs::raytrace
