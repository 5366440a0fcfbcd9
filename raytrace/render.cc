// RenderInto: a frame's tiles in parallel (TBB), each tile's samples in chunks of up to RayBatch::kMax rays
// (sampling.h: where they fall; camera_rays.h: the rays; RayScene: what they meet; film.h: how they add up), then
// its pixel-centre rays for the ground truth.
#include "raytrace/render.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#if defined(__SSE__)
#include <immintrin.h>
#endif
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "core/error.h"
#include "raytrace/camera_rays.h"
#include "raytrace/film.h"
#include "raytrace/sampling.h"

namespace hovs::raytrace {

void RenderOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(samples >= 1 && samples <= 4096, where + ".samples", "must be in 1..4096 (got ", samples, ")");
  HOVS_REQUIRE(std::isfinite(lens_radius) && lens_radius >= 0 && lens_radius <= kMaxApertureRadius,
               where + ".lens_radius", "must be in [0, ", kMaxApertureRadius, "] m (got ", lens_radius, ")");
  HOVS_REQUIRE(std::isfinite(focus_distance) && focus_distance > 0, where + ".focus_distance", "must be positive");
  HOVS_REQUIRE(std::isfinite(exposure_time) && exposure_time >= 0 && exposure_time <= kMaxExposureTime,
               where + ".exposure_time", "must be in [0, ", kMaxExposureTime, "] s (got ", exposure_time, ")");
  sensor.Check(where + ".sensor");
  truth_file.Check(where);
}

std::size_t FrameMemoryBytes(int width, int height, bool ground_truth) {
  const std::size_t npx = static_cast<std::size_t>(std::max(width, 0)) * static_cast<std::size_t>(std::max(height, 0));
  return npx * sizeof(float) * (3 + (ground_truth ? GroundTruth::kChannels : 0) + 3);
}

void CheckFrameMemory(const std::string& where, int width, int height, bool ground_truth, std::size_t held,
                      std::optional<std::size_t> available) {
  const std::size_t need = FrameMemoryBytes(width, height, ground_truth);
  if (need <= held) return;
  const std::string frame = "a " + std::to_string(width) + " x " + std::to_string(height) + " frame" +
                            (ground_truth ? " with ground truth" : "") + " (its buffers and the sensor image" +
                            (held > 0 ? ", less what its buffers hold" : "") + ")";
  RequireMemory(where, frame, need - held, available, "render fewer pixels or free memory");
}

RenderOptions OptionsForView(const RayScene& scene, const ViewCamera& camera, RenderOptions options) {
  if (options.lens_radius > 0 || camera.unit < 0 || camera.unit >= static_cast<int>(scene.description().units.size()))
    return options;
  const std::optional<ThinLens>& lens = scene.description().units[camera.unit].lens;
  if (!lens) return options;
  options.lens_radius = lens->ApertureRadius();
  options.focus_distance = std::min(lens->focus_distance, kFarFocus);
  return options;
}

void SampleRays(const RayScene& scene, const ViewCamera& camera, const RenderOptions& options, int n, const double* u,
                const double* v, const double* disc_x, const double* disc_y, const double* tau, RayBatch* out) {
  HOVS_REQUIRE(n >= 0 && n <= RayBatch::kMax, "SampleRays", "at most ", RayBatch::kMax, " points (got ", n, ")");
  HOVS_REQUIRE((disc_x == nullptr) == (disc_y == nullptr), "SampleRays", "aperture points need both coordinates");
  options.Check("render");
  const RayMaker maker(scene, camera, OptionsForView(scene, camera, options));
  double Mx[RayBatch::kMax], My[RayBatch::kMax], Mz[RayBatch::kMax];
  maker.MakeBatch(n, u, v, disc_x, disc_y, tau, out, Mx, My, Mz);
}

Frame Render(const RayScene& scene, const ViewCamera& camera, const RenderOptions& options) {
  Frame f;
  RenderInto(scene, camera, options, &f);
  return f;
}

namespace {

// The options' checks that depend on the scene (a moving unit must stay where Embree's precision holds), then
// the frame's buffers: sized (the memory checked first), zeroed only outside the region rendered (the tiles write
// every pixel and channel of theirs, the first touch in the rendering threads).
void PrepareFrame(const RayScene& scene, const ViewCamera& camera, const RenderOptions& options, const RayMaker& maker,
                  Frame* frame) {
  if (options.exposure_time > 0 && camera.unit >= 0) {
    const CatadioptricUnit& u = scene.description().units[camera.unit];
    const Vec3d end = u.WorldFromMirrorAt(options.exposure_time).translation;
    HOVS_REQUIRE(end.allFinite() && end.cwiseAbs().maxCoeff() <= kWorldExtent, "render.exposure_time", "unit ", u.name,
                 " moves beyond ", kWorldExtent, " m of the world origin during the exposure");
    HOVS_REQUIRE(options.exposure_time <= scene.MotionHorizon(), "render.exposure_time",
                 "the scene's units turn so "
                 "fast that motion blur covers at most ",
                 scene.MotionHorizon(), " s (got ", options.exposure_time, ")");
  }
  Frame& f = *frame;
  CheckFrameMemory(camera.unit >= 0 ? "render (unit " + scene.description().units[camera.unit].name + "'s camera)"
                                    : std::string("render (pinhole camera)"),
                   maker.width(), maker.height(), options.ground_truth,
                   sizeof(float) * (f.rgb.capacity() + f.truth.data.capacity()), AvailableMemoryBytes());
  f.width = maker.width(), f.height = maker.height();
  if (!options.ground_truth) f.truth.data.clear();
  const size_t npx = static_cast<size_t>(f.width) * f.height;
  f.rgb.resize(npx * 3);
  if (options.ground_truth) f.truth.data.resize(npx * GroundTruth::kChannels);
  const bool whole = options.region.Empty() || (options.region.x0 <= 0 && options.region.y0 <= 0 &&
                                                options.region.x1 >= f.width && options.region.y1 >= f.height);
  if (whole) return;
  for (PixelBuffer* b : {&f.rgb, &f.truth.data}) {  // zeroed in parallel (up to ~360 MB at full resolution)
    tbb::parallel_for(tbb::blocked_range<size_t>(0, b->size(), size_t(1) << 20),
                      [&](const tbb::blocked_range<size_t>& r) {
                        std::fill(b->begin() + static_cast<std::ptrdiff_t>(r.begin()),
                                  b->begin() + static_cast<std::ptrdiff_t>(r.end()), 0.0f);
                      });
  }
}

// The region rendered, in tiles of kTile x kTile pixels.
struct TileGrid {
  static constexpr int kTile = 16;
  RenderOptions::Region roi;
  int tiles_x = 0, tiles_y = 0;
  TileGrid(const RenderOptions::Region& region, int width, int height) : roi(region) {
    if (roi.Empty()) roi = {0, 0, width, height};
    roi.x0 = std::max(0, roi.x0), roi.y0 = std::max(0, roi.y0);
    roi.x1 = std::min(width, roi.x1), roi.y1 = std::min(height, roi.y1);
    HOVS_REQUIRE(!roi.Empty(), "render.region", "the region does not overlap the image");
    tiles_x = (roi.x1 - roi.x0 + kTile - 1) / kTile, tiles_y = (roi.y1 - roi.y0 + kTile - 1) / kTile;
  }
  int count() const { return tiles_x * tiles_y; }
};

// The progress bar on stderr, in steps of 5 %: every thread counts its tiles, and of the threads that reach a
// step the one that advances the last printed step prints it.
class Progress {
 public:
  Progress(bool on, int total) : on_(on), total_(total) {}
  void TileDone() {
    if (!on_) return;
    const int d = ++done_;  // (only here: an atomic shared by all threads costs about 0.6 % of a frame)
    const int percent = static_cast<int>(100.0 * d / total_);
    if (percent % 5 != 0) return;
    int last = printed_.load();
    while (percent > last) {
      if (!printed_.compare_exchange_weak(last, percent)) continue;
      std::fprintf(stderr, "\rrender [%-20s] %3d%%", std::string(percent / 5, '#').c_str(), percent);
      if (percent == 100) std::fprintf(stderr, "\n");
      return;
    }
  }

 private:
  bool on_;
  int total_;
  std::atomic<int> done_{0}, printed_{-1};
};

// What one TBB task renders: tiles, each as its colour samples in chunks of whole pixels (or of part of one
// pixel) and its pixel-centre rays for the ground truth. It owns one batch of up to kMax rays in
// structure-of-arrays form, reused for every chunk.
class TileRenderer {
 public:
  static constexpr int kMax = RayBatch::kMax;

  // blur: the samples get times in the exposure (a unit's camera with an exposure time).
  TileRenderer(const RayScene& scene, const RayMaker& maker, const RenderOptions& options, bool blur, Frame* frame)
      : scene_(scene),
        maker_(maker),
        o_(options),
        f_(*frame),
        batch_(std::make_unique<RayBatch>()),
        batch_f_(maker.single() ? std::make_unique<RayBatchF>() : nullptr),
        sc_(std::make_unique<Scratch>()) {
    n_ = options.samples;
    grid_ = static_cast<int>(std::lround(std::sqrt(n_)));
    stratified_ = grid_ * grid_ == n_;
    inv_grid_ = 1.0 / grid_;
    weight_ = 1.0f / n_;
    seed_mix_ = options.seed * 0x100000001B3ull;
    per_chunk_ = kMax / n_;
    lens_ = options.lens_radius > 0;
    blur_ = blur;
  }

  // Tile (x0, y0) .. (x1, y1), exclusive.
  void Render(int x0, int y0, int x1, int y1) {
    ColourSamples(x0, y0, x1, y1);
    if (o_.ground_truth) GroundTruthRays(x0, y0, x1, y1);
  }
  uint64_t rays() const { return rays_; }
  uint64_t embree_rays() const { return embree_rays_; }

 private:
  struct Scratch {
    double u[kMax], v[kMax], Mx[kMax], My[kMax], Mz[kMax], tau[kMax];
    double nx[kMax], ny[kMax], col_x[kMax], row_y[kMax];  // pixel centres' normalised coordinates
    double disc_x[kMax], disc_y[kMax];                    // thin-lens aperture points (unit disc)
    int px[kMax];
    // The chunk's pixels: index in the frame, centre.
    int pixel[kMax];
    int run_at[kMax], run_len[kMax];  // runs of neighbouring pixels (along a tile row) in the chunk
    int pixel_x[kMax], pixel_y[kMax];
    float rgb[3 * kMax];
    HitBatch hits;                                           // the ground-truth rays' hits
    alignas(64) float truth[GroundTruth::kChannels * kMax];  // their ground truth, channel by channel
  };

  // The samples of the tile in chunks of P whole pixels (or of part of one pixel, P = 1, when it has more
  // samples than a chunk holds), ordered by sample index, then pixel: sample s of the chunk's pixel q is
  // k = (s - s_begin) P + q. So a packet holds one stratum of 16 neighbouring pixels, and each pixel's sum
  // below runs over contiguous rows of colours.
  void ColourSamples(int x0, int y0, int x1, int y1) {
    Scratch& sc = *sc_;
    const int tile_px = (x1 - x0) * (y1 - y0);
    int x = x0, y = y0, s0 = 0;
    for (int p0 = 0; p0 < tile_px;) {
      const int pixels = std::min(per_chunk_, tile_px - p0), count = std::min(n_ - s0, kMax);
      const int P = per_chunk_ > 0 ? pixels : 1, m = per_chunk_ > 0 ? pixels * n_ : count;
      const int s_begin = per_chunk_ > 0 ? 0 : s0, s_end = per_chunk_ > 0 ? n_ : s0 + count;
      int xq = x, yq = y;  // the chunk's pixels, in runs along the tile's rows (run r: run_at[r] .. + run_len[r])
      int runs = 0;
      for (int q = 0; q < P;) {
        const int len = std::min(x1 - xq, P - q), base = yq * f_.width + xq;
        for (int i = 0; i < len; ++i) {
          sc.pixel[q + i] = base + i;
          sc.pixel_x[q + i] = xq + i, sc.pixel_y[q + i] = yq;
        }
        sc.run_at[runs] = q, sc.run_len[runs++] = len;
        q += len;
        if ((xq += len) == x1) xq = x0, ++yq;
      }
      TraceChunk(P, m, s_begin, s_end);
      // Each pixel's samples summed in order, weighted (w r0 + w r1 + ...: the first sample starts the sum, so
      // the frame needs no zeroing; a pixel split over chunks adds to what its earlier chunks left): over the
      // chunk's colour rows at once, then written per run of neighbouring pixels.
      for (int r = 0; r < runs; ++r) {
        const int qa = sc.run_at[r];
        SumSamples(3 * sc.run_len[r], s_end - s_begin, 3 * P, weight_, sc.rgb + 3 * qa, s_begin > 0,
                   &f_.rgb[3 * static_cast<size_t>(sc.pixel[qa])]);
      }
      if (per_chunk_ > 0) {
        p0 += pixels;
        x = xq, y = yq;
      } else if ((s0 += count) == n_) {  // the pixel's last chunk
        s0 = 0, ++p0;
        if (++x == x1) x = x0, ++y;
      }
    }
  }

  // The colours of a chunk's m samples (samples s_begin .. s_end - 1 of its P pixels) into sc.rgb.
  void TraceChunk(int P, int m, int s_begin, int s_end) {
    Scratch& sc = *sc_;
    JitteredSamples(P, s_begin, s_end, grid_, seed_mix_, stratified_, inv_grid_, sc.pixel, sc.pixel_x, sc.pixel_y, sc.u,
                    sc.v);
    if (lens_ || blur_) {  // aperture points (uniform on the unit disc) and exposure times
      LensSamples(P, s_begin, s_end, seed_mix_, lens_, blur_ ? o_.exposure_time : 0.0, sc.pixel, sc.disc_x, sc.disc_y,
                  sc.tau);
    }
    if (batch_f_) {  // (every ray of this path is valid: MakeBatchF has no domain limit)
      maker_.MakeBatchF(m, sc.u, sc.v, batch_f_.get());
      embree_rays_ += static_cast<uint64_t>(scene_.Colours(*batch_f_, sc.rgb));
      rays_ += static_cast<uint64_t>(m);
      return;
    }
    maker_.MakeBatch(m, sc.u, sc.v, lens_ ? sc.disc_x : nullptr, lens_ ? sc.disc_y : nullptr, blur_ ? sc.tau : nullptr,
                     batch_.get(), sc.Mx, sc.My, sc.Mz);
    embree_rays_ += static_cast<uint64_t>(scene_.Colours(*batch_, sc.rgb));
    for (int k = 0; k < m; ++k) rays_ += batch_->valid[k];
  }

  // The pixel-centre rays of the tile, without colour. Without distortion their normalised coordinates are a
  // column's and a row's (the same divisions as PixelRays, once per column and row).
  void GroundTruthRays(int x0, int y0, int x1, int y1) {
    Scratch& sc = *sc_;
    const int tw = x1 - x0, tile_px = tw * (y1 - y0);
    const PinholeCamera<double>& gc = maker_.camera();
    const bool separable = gc.distortion.IsZero();
    if (separable) {
      for (int i = 0; i < tw; ++i) sc.col_x[i] = (static_cast<double>(x0 + i) - gc.cx) / gc.fx;
      for (int j = 0; j < y1 - y0; ++j) sc.row_y[j] = (static_cast<double>(y0 + j) - gc.cy) / gc.fy;
    }
    int gx = x0, gy = y0;
    for (int p0 = 0; p0 < tile_px; p0 += kMax) {
      const int m = std::min(kMax, tile_px - p0);
      int runs = 0;
      for (int k = 0; k < m;) {  // in runs along the tile's rows
        const int len = std::min(x1 - gx, m - k), base = gy * f_.width + gx;
        sc.run_at[runs] = k, sc.run_len[runs++] = len;
        for (int i = 0; i < len; ++i) sc.px[k + i] = base + i;
        if (!separable) {
          for (int i = 0; i < len; ++i) sc.u[k + i] = gx + i, sc.v[k + i] = gy;
        } else {
          std::copy(sc.col_x + (gx - x0), sc.col_x + (gx - x0) + len, sc.nx + k);
          std::fill(sc.ny + k, sc.ny + k + len, sc.row_y[gy - y0]);
        }
        k += len;
        if ((gx += len) == x1) gx = x0, ++gy;
      }
      maker_.MakeBatch(m, sc.u, sc.v, nullptr, nullptr, nullptr, batch_.get(), sc.Mx, sc.My, sc.Mz,
                       separable ? sc.nx : nullptr, separable ? sc.ny : nullptr);
      embree_rays_ += static_cast<uint64_t>(scene_.Geometry(*batch_, &sc.hits));
      const HitBatch& H = sc.hits;
      static_assert(GroundTruth::kChannels == 12, "the pixel below is 12 floats");
      GroundTruthLanes(m, batch_->valid, batch_->from_mirror, H.hit, H.object_id, maker_.viewpoint().data(), H.px, H.py,
                       H.pz, H.nx, H.ny, H.nz, sc.Mx, sc.My, sc.Mz, sc.truth);
      for (int k = 0; k < m; ++k) rays_ += batch_->valid[k];
      // Every channel of every pixel is written (the buffer is not zeroed first), in runs along the tile's rows.
      for (int r = 0; r < runs; ++r) {
        const int k = sc.run_at[r], e = k + sc.run_len[r];
        float* v = &f_.truth.data[static_cast<size_t>(sc.px[k]) * GroundTruth::kChannels];
        for (int i = k; i < e; ++i, v += GroundTruth::kChannels) StoreGroundTruthPixel(sc.truth + i, v);
      }
    }
  }

  const RayScene& scene_;
  const RayMaker& maker_;
  const RenderOptions& o_;
  Frame& f_;
  std::unique_ptr<RayBatch> batch_;
  std::unique_ptr<RayBatchF> batch_f_;
  std::unique_ptr<Scratch> sc_;
  int n_ = 1, grid_ = 1, per_chunk_ = 0;
  bool stratified_ = true, lens_ = false, blur_ = false;
  double inv_grid_ = 1;
  float weight_ = 1;
  uint64_t seed_mix_ = 0;
  uint64_t rays_ = 0, embree_rays_ = 0;
};

}  // namespace

void RenderInto(const RayScene& scene, const ViewCamera& camera, const RenderOptions& view_options, Frame* frame) {
  view_options.Check("render");
  const RenderOptions options = OptionsForView(scene, camera, view_options);
  options.Check("render (the unit's lens)");
  const auto start = std::chrono::steady_clock::now();
  const RayMaker maker(scene, camera, options);
  PrepareFrame(scene, camera, options, maker, frame);
  const TileGrid tiles(options.region, frame->width, frame->height);
  const bool blur = options.exposure_time > 0 && camera.unit >= 0;
  std::atomic<uint64_t> rays{0}, embree_rays{0};
  Progress progress(options.progress && isatty(STDERR_FILENO), tiles.count());
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles.count()), [&](const tbb::blocked_range<int>& range) {
    TileRenderer task(scene, maker, options, blur, frame);
    for (int ti = range.begin(); ti != range.end(); ++ti) {
      const int x0 = tiles.roi.x0 + (ti % tiles.tiles_x) * TileGrid::kTile;
      const int y0 = tiles.roi.y0 + (ti / tiles.tiles_x) * TileGrid::kTile;
      task.Render(x0, y0, std::min(x0 + TileGrid::kTile, tiles.roi.x1), std::min(y0 + TileGrid::kTile, tiles.roi.y1));
      progress.TileDone();
    }
#if defined(__SSE__)
    _mm_sfence();  // the streamed ground truth, ordered before the task ends
#endif
    rays += task.rays();
    embree_rays += task.embree_rays();
  });
  frame->rays = rays;
  frame->embree_rays = embree_rays;
  frame->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::map<std::string, std::string> RaytraceVersions() {
  std::map<std::string, std::string> v = io::IoVersions();
  v["embree"] = RTC_VERSION_STRING;
  return v;
}

}  // namespace hovs::raytrace
