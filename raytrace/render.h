// Rendering: stratified supersampling with the core's pixel convention, ground truth at pixel centres,
// multithreaded over tiles (TBB) with 16-ray packets, and a sensor model (vignetting, seeded shot and read
// noise, RGGB Bayer mosaic, 8- or 16-bit output).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "core/large_pages.h"
#include "io/image_io.h"
#include "raytrace/scene.h"

namespace hovs::raytrace {

struct SensorOptions {
  double gain = 1.0;        // linear scale before quantisation
  double vignetting = 0.0;  // 0: none; v: brightness (1 - v) at the image corner, cos^4-shaped
  double full_well = 0.0;   // electrons at white; > 0 enables shot noise
  double read_noise = 0.0;  // electrons (standard deviation); needs full_well > 0
  bool bayer = false;       // write one RGGB mosaic channel instead of RGB
  int bit_depth = 8;        // 8 or 16
  void Check(const std::string& where) const;
};

// What a frame's ground-truth file holds: groups of GroundTruth's channels (Z, P, N, id, mask, M below; a group
// is its channels in kNames order) and OpenEXR's lossless compression. The default, Z N id mask with PIZ, is
// 24 MB for a 2750 x 2200 frame of the reference scene where all twelve channels take 82 MB: the world point P
// and the mirror point M (about 30 MB each, as incompressible as any float position) are written on request.
// Corner truth lives in the JSON sidecar whatever the file holds; with no group, no EXR is written.
struct TruthFileOptions {
  std::vector<std::string> groups = {"Z", "N", "id", "mask"};
  std::string compression = "piz";
  static const std::vector<std::string>& AllGroups();     // Z P N id mask M
  static const std::vector<std::string>& Compressions();  // none rle zips zip piz (lossless for float data)
  // "default", "all", "none", or groups separated by commas in any order (written in AllGroups' order). Throws
  // hovs::Error naming `where` and the word it does not know.
  static std::vector<std::string> ParseGroups(const std::string& text, const std::string& where);
  std::vector<int> Channels() const;  // indices into GroundTruth::kNames, ascending
  std::string GroupsText() const;     // "Z,N,id,mask"; "none" without any
  void Check(const std::string& where) const;
};

struct RenderOptions {
  int samples = 4;           // per pixel; a perfect square gives a stratified grid, otherwise jittered
  uint64_t seed = 1;         // sample jitter and sensor noise
  bool ground_truth = true;  // per-pixel ground truth from the pixel-centre ray (pinhole, time 0)
  // Thin-lens defocus of the camera (catadioptric or pinhole): lens radius in metres (0: pinhole) and the
  // distance from the lens along its optical axis to the plane in focus (for a catadioptric camera, the mirror's
  // virtual image lies a little beyond the mirror: about 2c). With lens_radius 0, a unit that has a lens
  // (CatadioptricUnit::lens) is rendered through it (OptionsForView).
  double lens_radius = 0.0;
  double focus_distance = 0.13;
  // Motion blur: the exposure time (s); each sample sees the unit at a random time in [0, exposure] moving
  // with the unit's velocity and angular velocity. Every moving unit's parts (its camera body, lens face, mirror
  // and mount, as seen in its own mirror or by another unit) are met where they are at that time.
  double exposure_time = 0.0;
  bool progress = false;  // progress bar on stderr
  // Render only pixels with x0 <= x < x1, y0 <= y < y1 (others stay black, ground truth zero). Empty: all.
  struct Region {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    bool Empty() const { return x1 <= x0 || y1 <= y0; }
  } region;
  SensorOptions sensor;
  TruthFileOptions truth_file;  // what the dataset writers store of the ground truth
  void Check(const std::string& where) const;
};

// What looks: a catadioptric unit of the scene, or a plain pinhole camera anywhere.
struct ViewCamera {
  int unit = 0;                   // >= 0: the scene's unit
  PinholeCamera<double> pinhole;  // used when unit < 0
  Rigid3d world_from_cam;         // used when unit < 0
  static ViewCamera Unit(int u) { return ViewCamera{u, {}, {}}; }
  static ViewCamera Pinhole(const PinholeCamera<double>& cam, const Rigid3d& world_from_cam) {
    return ViewCamera{-1, cam, world_from_cam};
  }
};

// Ground truth channels (pixel centres). Frames and meaning:
//   Z       range (m) from the unit's viewpoint F1 (pinhole: the camera centre) to the surface seen; +inf: sky
//   P.X/Y/Z world point seen (world frame); 0 for sky
//   N.X/Y/Z surface normal (world frame), facing the viewer; 0 for sky
//   id      object id (0 sky, 1 mirror mount, 2 camera body, 3 mirror back, 4.. scene objects in order)
//   mask    1 where the pixel's ray is reflected by the mirror (inside the rim) and does not see the camera
//   M.X/Y/Z the mirror reflection point in the unit's mirror frame (0 where mask is 0 and the rim is missed)
// The frame's buffers: left uninitialised by resize() (the renderer fills frames in parallel instead of zeroing
// hundreds of megabytes on one thread), in huge pages when large (io/image_io.h).
using io::PixelBuffer;

struct GroundTruth {
  static constexpr int kChannels = 12;
  static const char* const kNames[kChannels];
  PixelBuffer data;  // interleaved, kChannels per pixel
};

struct Frame {
  int width = 0, height = 0;
  PixelBuffer rgb;    // linear radiance, 3 per pixel, before the sensor model
  GroundTruth truth;  // empty if not requested
  // Rays traced: one per valid sample and per ground-truth pixel, each the camera ray and, where it meets the
  // mirror, its reflection; Embree or an analytic surface (the unit's own mount ring) ends it.
  uint64_t rays = 0;
  // Of those, the rays given to Embree (the others end analytically: camera rays past the rim on the unit's own
  // mount ring when nothing can lie in between). rtcIntersect16's raw figure is comparable with these.
  uint64_t embree_rays = 0;
  double seconds = 0;
};

// The options a view is rendered with: with options.lens_radius 0 and a unit that has a lens, its aperture radius
// and focus distance (a lens focused at infinity: rays of one pixel parallel, the focus plane at kFarFocus).
constexpr double kFarFocus = 1e9;  // m
RenderOptions OptionsForView(const RayScene& scene, const ViewCamera& camera, RenderOptions options);

// A new frame. Its large buffers come from core/large_pages.h, so in a process that keeps freed large buffers
// (KeepFreedLargePages; the hovs command does) a frame freed before this one lends it its memory, already mapped.
Frame Render(const RayScene& scene, const ViewCamera& camera, const RenderOptions& options);
// Render into *frame, reusing its buffers where large enough: a sequence of frames (a dataset) then touches its
// memory once. At 2750 x 2200 with ground truth that first touch (362 MB, in huge pages) cost 90-250 ms per
// frame on a Zen 5 VM (in 4 KiB pages, before core/large_pages.h, ~650 ms there).
void RenderInto(const RayScene& scene, const ViewCamera& camera, const RenderOptions& options, Frame* frame);

// The rays RenderInto traces for n <= RayBatch::kMax image points (u, v) of a camera, with thin-lens aperture
// points (disc_x[i], disc_y[i]) on the unit disc (null: the aperture centre) and times tau[i] in the exposure
// (null: 0), made as the renderer makes its double-precision samples (thin lens, motion blur; without either, the
// ground-truth rays of pixel centres): for tests and tools that check the renderer's geometry. out->from_mirror
// tells which rays leave the unit's mirror.
void SampleRays(const RayScene& scene, const ViewCamera& camera, const RenderOptions& options, int n, const double* u,
                const double* v, const double* disc_x, const double* disc_y, const double* tau, RayBatch* out);

// The memory a width x height frame takes with what is made from it: its RGB and, with ground truth, its 12
// channels as floats, and the sensor image (ApplySensor: up to 3 floats per pixel). 2750 x 2200 with ground
// truth: 436 MB.
std::size_t FrameMemoryBytes(int width, int height, bool ground_truth);
// RenderInto's check before it takes a frame's memory: a frame whose FrameMemoryBytes, less the `held` bytes its
// buffers already have, exceeds `available` (core's AvailableMemoryBytes; nullopt: unknown, no check) is refused
// with an error naming its size and both amounts, where Linux would let it start and kill the process later.
void CheckFrameMemory(const std::string& where, int width, int height, bool ground_truth, std::size_t held,
                      std::optional<std::size_t> available);

// The sensor model applied to a frame: 3 channels (or 1 for Bayer), values in [0, 1] before quantisation.
// The result is a PixelBuffer: written in parallel, in huge pages (no single-threaded zeroing of 72 MB first).
PixelBuffer ApplySensor(const Frame& frame, const SensorOptions& sensor, uint64_t seed, int* channels);

// The ground truth of a frame as OpenEXR (io::WriteExr): the channels `file` selects (all twelve by default) with
// its compression, `metadata` stored as "hovs:<key>" string attributes.
void WriteGroundTruthExr(const std::filesystem::path& path, const Frame& frame,
                         const std::vector<std::pair<std::string, std::string>>& metadata,
                         const TruthFileOptions& file = TruthFileOptions{TruthFileOptions::AllGroups(), "piz"});

// Versions of the libraries that make a render, for the outputs that record what made them: "embree" (the
// headers built against; Debian ships them with the library) and io's (OpenImageIO, OpenEXR, libpng, libjpeg).
std::map<std::string, std::string> RaytraceVersions();

}  // namespace hovs::raytrace
