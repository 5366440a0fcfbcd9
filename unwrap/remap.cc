#include "unwrap/remap.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include <immintrin.h>

#include "core/error.h"
#include "core/vector_clones.h"
#include "unwrap/remap_kernels.h"

namespace hovs::unwrap {
namespace {

// ---------------------------------------------------------------------------------------------------------
// Source planes. A plane is one channel sampled on a regular grid inside an interleaved or mosaic buffer:
// element (i, j) is at data + j * ystep + i * xstep.
struct Plane {
  const uint8_t* data;
  int w, h;
  ptrdiff_t xstep, ystep;
  int at(int i, int j) const {
    i = std::clamp(i, 0, w - 1);
    j = std::clamp(j, 0, h - 1);
    return data[j * ystep + i * xstep];
  }
};

inline float Cubic(float t, float* w) {
  // Keys (a = -0.5) weights for taps at -1, 0, 1, 2 from the sample at fractional position t in [0, 1).
  const float a = -0.5f;
  const float t2 = t * t, t3 = t2 * t;
  w[0] = a * (t3 - 2 * t2 + t);
  w[1] = (a + 2) * t3 - (a + 3) * t2 + 1;
  w[2] = -(a + 2) * t3 + (2 * a + 3) * t2 - a * t;
  w[3] = a * (-t3 + t2);
  return 0;
}

// Clamped sample of a plane at (x, y) in plane coordinates.
float SamplePlane(const Plane& p, float x, float y, Interpolation m) {
  if (m == Interpolation::kNearest) return float(p.at(int(std::lround(x)), int(std::lround(y))));
  const float fx0 = std::floor(x), fy0 = std::floor(y);
  const int ix = int(fx0), iy = int(fy0);
  const float tx = x - fx0, ty = y - fy0;
  if (m == Interpolation::kBilinear) {
    const float top = p.at(ix, iy) * (1 - tx) + p.at(ix + 1, iy) * tx;
    const float bot = p.at(ix, iy + 1) * (1 - tx) + p.at(ix + 1, iy + 1) * tx;
    return top * (1 - ty) + bot * ty;
  }
  float wx[4], wy[4];
  Cubic(tx, wx);
  Cubic(ty, wy);
  float acc = 0;
  for (int j = 0; j < 4; ++j) {
    float row = 0;
    for (int i = 0; i < 4; ++i) row += wx[i] * p.at(ix - 1 + i, iy - 1 + j);
    acc += wy[j] * row;
  }
  return acc;
}

inline uint8_t Saturate(float v) { return static_cast<uint8_t>(std::clamp(std::lround(v), 0l, 255l)); }

// ---------------------------------------------------------------------------------------------------------
// Samplers: called with 16.16 coordinates at the tile's level, write one output pixel.

// Generic: any format and interpolation, clamped at the borders.
struct GenericSampler {
  Plane planes[4];
  int num_planes = 1;  // 1 grey, 3 RGB, 4 Bayer (R, G1, G2, B)
  bool bayer = false;
  Interpolation m;
  void operator()(int32_t xf, int32_t yf, uint8_t* o) const {
    const float x = xf * (1.f / 65536), y = yf * (1.f / 65536);
    if (!bayer) {
      for (int c = 0; c < num_planes; ++c) o[c] = Saturate(SamplePlane(planes[c], x, y, m));
      return;
    }
    // Mosaic positions of the colour grids: R (2i, 2j), G1 (2i + 1, 2j), G2 (2i, 2j + 1), B (2i + 1, 2j + 1).
    const float hx = 0.5f * x, hy = 0.5f * y, hx1 = 0.5f * (x - 1), hy1 = 0.5f * (y - 1);
    o[0] = Saturate(SamplePlane(planes[0], hx, hy, m));
    o[1] = Saturate(0.5f * (SamplePlane(planes[1], hx1, hy, m) + SamplePlane(planes[2], hx, hy1, m)));
    o[2] = Saturate(SamplePlane(planes[3], hx1, hy1, m));
  }
};

template <int C>
struct NearestSampler {
  const uint8_t* data;
  ptrdiff_t stride;
  void operator()(int32_t xf, int32_t yf, uint8_t* o) const {
    const uint8_t* p = data + ((yf + 0x8000) >> 16) * stride + ((xf + 0x8000) >> 16) * C;
    for (int c = 0; c < C; ++c) o[c] = p[c];
  }
};

// Row functors: f(xs, ys, n, out) samples n pixels of one output row.
// Tile(...) does a whole interp tile, or returns false to have it done row by row.
template <class PixelSampler, int OC>
struct PerPixel {
  PixelSampler s;
  void operator()(const kernels::RowCoords& c, int i0, int n, uint8_t* o) const {
    for (int i = 0; i < n; ++i) s(c.X(i0 + i), c.Y(i0 + i), o + i * OC);
  }
  bool Tile(const hovs::unwrap::Tile&, int, int, int, uint8_t*, ptrdiff_t) const { return false; }
};
using RowKernel = void (*)(const uint8_t*, ptrdiff_t, const kernels::RowCoords&, int, int, uint8_t*);
using TileKernel = void (*)(const uint8_t*, ptrdiff_t, const hovs::unwrap::Tile&, int, int, int, uint8_t*, ptrdiff_t);
struct FastRow {
  RowKernel kernel;
  TileKernel tile;
  const uint8_t* data;
  ptrdiff_t stride;
  void operator()(const kernels::RowCoords& c, int i0, int n, uint8_t* o) const { kernel(data, stride, c, i0, n, o); }
  bool Tile(const hovs::unwrap::Tile& t, int T, int nu, int nv, uint8_t* out, ptrdiff_t ostride) const {
    tile(data, stride, t, T, nu, nv, out, ostride);
    return true;
  }
};

// Walks one tile's rows: interp tiles evaluate their coordinates per row, dense tiles read them; runs of valid
// pixels go to the row functor, invalid pixels are written as 0.
// base: the tile's first output pixel; ostride: bytes per output row.
template <int OC, class Row>
void WalkTile(const ViewTable& vt, const Tile& t, int T, int nu, int nv, uint8_t* base, size_t ostride, const Row& f) {
  int32_t xs[64], ys[64];
  if (t.kind == TileKind::kInterp) {
    if (f.Tile(t, T, nu, nv, base, static_cast<ptrdiff_t>(ostride))) return;
    kernels::RowCoords c;
    // Rows are written into a small local buffer first, then copied out (measured: about 8 % faster than
    // writing each pixel into the view directly).
    alignas(64) uint8_t local[64 * OC + 32];
    for (int j = 0; j < nv; ++j) {
      c.poly = InterpRowPoly(t, T, j);
      f(c, 0, nu, local);
      std::memcpy(base + j * ostride, local, size_t(nu) * OC);
    }
    return;
  }
  kernels::RowCoords c;
  c.xs = xs, c.ys = ys;
  const int32_t* d = vt.dense.data() + size_t(t.dense_index) * 2;
  for (int j = 0; j < nv; ++j) {
    uint8_t* o = base + j * ostride;
    const int32_t* dj = d + 2 * j * T;
    int i = 0;
    while (i < nu) {
      if (dj[2 * i] == kInvalidCoordinate) {
        std::memset(o + i * OC, 0, OC);
        ++i;
        continue;
      }
      int n = 0;
      while (i + n < nu && dj[2 * (i + n)] != kInvalidCoordinate) {
        xs[n] = dj[2 * (i + n)];
        ys[n] = dj[2 * (i + n) + 1];
        ++n;
      }
      f(c, 0, n, o + i * OC);
      i += n;
    }
  }
}

// How many tiles ahead of the one being remapped the source is prefetched.
constexpr int kPrefetchTiles = 2;

// A pyramid level as an image (levels are grey or RGB).
ImageView LevelView(const Image8& level) {
  return level.View(level.channels == 1 ? PixelFormat::kGray8 : PixelFormat::kRgb8);
}

// The image a tile samples: the frame, or the pyramid level the tile asks for.
ImageView TileSource(const ImageView& src, const std::vector<Image8>& pyramid, const Tile& t) {
  return t.level == 0 ? src : LevelView(pyramid[t.level - 1]);
}

// Asks the caches for the source region an interp tile will sample (the bounding box of its nodes).
void PrefetchTile(const ImageView& src, const std::vector<Image8>& pyramid, const Tile& t) {
  if (t.kind != TileKind::kInterp || !t.inside) return;
  const ImageView im = TileSource(src, pyramid, t);
  const uint8_t* data = im.data;
  const size_t stride = im.stride;
  const int bpp = im.format == PixelFormat::kRgb8 ? 3 : 1;
  float x0 = t.x[0], x1 = t.x[0], y0 = t.y[0], y1 = t.y[0];
  for (int k = 1; k < 9; ++k) {
    x0 = std::min(x0, t.x[k]), x1 = std::max(x1, t.x[k]);
    y0 = std::min(y0, t.y[k]), y1 = std::max(y1, t.y[k]);
  }
  // inside: every tap lies at least 2 px inside the image, so the box plus one pixel is inside too.
  const int h = im.height;
  const int r0 = std::max(0, int(y0) - 1), r1 = std::min(h - 1, int(y1) + 2);
  const size_t c0 = size_t(std::max(0, int(x0) - 1)) * bpp, c1 = std::min(size_t(int(x1) + 2) * bpp, stride - 1);
  for (int r = r0; r <= r1; ++r) {
    const uint8_t* row = data + size_t(r) * stride;
    for (size_t c = c0 & ~size_t(63); c <= c1; c += 64) __builtin_prefetch(row + c);
  }
}

// Copies n bytes to dst with non-temporal stores (whole aligned 16-byte blocks; the ends with plain stores): the
// views are written once and not read back here, so they need not be read into the caches first nor evict the
// source frame from them.
void StreamCopy(const uint8_t* src, size_t n, uint8_t* dst) {
  const size_t head = std::min(n, size_t((16 - (reinterpret_cast<uintptr_t>(dst) & 15)) & 15));
  std::memcpy(dst, src, head);
  size_t k = head;
  for (; k + 16 <= n; k += 16)
    _mm_stream_si128(reinterpret_cast<__m128i*>(dst + k), _mm_loadu_si128(reinterpret_cast<const __m128i*>(src + k)));
  std::memcpy(dst + k, src + k, n - k);
  _mm_sfence();
}

// Rows of the pyramid (integer loops: every compiled copy gives the same bytes).
// s[k] = a[k] + b[k], k < n: the vertical sums of two rows.
HOVS_VECTOR_CLONES void AddRows(const uint8_t* a, const uint8_t* b, int n, uint16_t* s) {
  for (int k = 0; k < n; ++k) s[k] = static_cast<uint16_t>(a[k] + b[k]);
}
// Output pixel i of a grey / RGB row from the vertical sums of its 2 W source pixels.
HOVS_VECTOR_CLONES void PairSumsGray(const uint16_t* s, int W, uint8_t* o) {
  for (int i = 0; i < W; ++i) o[i] = static_cast<uint8_t>((s[2 * i] + s[2 * i + 1] + 2) >> 2);
}
HOVS_VECTOR_CLONES void PairSumsRgb(const uint16_t* s, int W, uint8_t* o) {
  for (int i = 0; i < W; ++i) {
    o[3 * i] = static_cast<uint8_t>((s[6 * i] + s[6 * i + 3] + 2) >> 2);
    o[3 * i + 1] = static_cast<uint8_t>((s[6 * i + 1] + s[6 * i + 4] + 2) >> 2);
    o[3 * i + 2] = static_cast<uint8_t>((s[6 * i + 2] + s[6 * i + 5] + 2) >> 2);
  }
}
// The RGGB cells of mosaic rows a (R G) and b (G B) as RGB pixels.
HOVS_VECTOR_CLONES void BayerCells(const uint8_t* a, const uint8_t* b, int W, uint8_t* o) {
  for (int i = 0; i < W; ++i) {
    o[3 * i] = a[2 * i];
    o[3 * i + 1] = static_cast<uint8_t>((a[2 * i + 1] + b[2 * i] + 1) >> 1);
    o[3 * i + 2] = b[2 * i + 1];
  }
}

}  // namespace

void DownsampleHalf(const ImageView& in, Image8* out) {
  HOVS_REQUIRE(in.data != nullptr && in.width > 0 && in.height > 0, "pyramid input", "no image data");
  const bool bayer = in.format == PixelFormat::kBayerRggb8;
  const int Cin = in.format == PixelFormat::kRgb8 ? 3 : 1;
  HOVS_REQUIRE(in.stride >= size_t(in.width) * Cin, "pyramid input", "row stride ", in.stride,
               " is smaller than a row of ", in.width * Cin, " bytes");
  HOVS_REQUIRE(!bayer || (in.width % 2 == 0 && in.height % 2 == 0), "pyramid input",
               "a Bayer mosaic needs an even width and height");
  const int W = (in.width + 1) / 2, H = (in.height + 1) / 2, C = bayer ? 3 : Cin;
  out->width = W, out->height = H, out->channels = C;
  out->data.resize(size_t(W) * H * C);
  tbb::parallel_for(tbb::blocked_range<int>(0, H, 32), [&](const tbb::blocked_range<int>& rows) {
    std::vector<uint16_t> sums(bayer ? 0 : size_t(2 * W) * Cin);
    for (int j = rows.begin(); j < rows.end(); ++j) {
      const uint8_t* a = in.data + size_t(2 * j) * in.stride;
      const uint8_t* b = in.data + size_t(std::min(2 * j + 1, in.height - 1)) * in.stride;
      uint8_t* o = out->data.data() + size_t(j) * W * C;
      if (bayer) {
        BayerCells(a, b, W, o);
        continue;
      }
      const int n = in.width * Cin;
      AddRows(a, b, n, sums.data());
      if (in.width % 2) std::copy(sums.data() + n - Cin, sums.data() + n, sums.data() + n);  // last pixel twice
      if (Cin == 3) {
        PairSumsRgb(sums.data(), W, o);
      } else {
        PairSumsGray(sums.data(), W, o);
      }
    }
  });
}

const char* ToString(PixelFormat f) {
  return f == PixelFormat::kGray8 ? "gray" : f == PixelFormat::kRgb8 ? "rgb" : "bayer_rggb";
}
const char* ToString(Interpolation i) {
  return i == Interpolation::kNearest ? "nearest" : i == Interpolation::kBilinear ? "bilinear" : "bicubic";
}
PixelFormat ParsePixelFormat(const std::string& s) {
  if (s == "gray" || s == "grey" || s == "mono8") return PixelFormat::kGray8;
  if (s == "rgb") return PixelFormat::kRgb8;
  if (s == "bayer_rggb" || s == "bayerrg8" || s == "bayer") return PixelFormat::kBayerRggb8;
  throw Error("pixel format '" + s + "'", "unknown (known: gray, rgb, bayer_rggb)");
}
Interpolation ParseInterpolation(const std::string& s) {
  if (s == "nearest") return Interpolation::kNearest;
  if (s == "bilinear") return Interpolation::kBilinear;
  if (s == "bicubic") return Interpolation::kBicubic;
  throw Error("interpolation '" + s + "'", "unknown (known: nearest, bilinear, bicubic)");
}

Remapper::Remapper(const RemapTable& table) : table_(table) {}

void Remapper::Prepare(const ImageView& src) {
  HOVS_REQUIRE(src.data != nullptr, "remap input", "no image data");
  HOVS_REQUIRE(src.width == table_.source_width && src.height == table_.source_height, "remap input", "the image is ",
               src.width, " x ", src.height, " but the mapping was built for ", table_.source_width, " x ",
               table_.source_height, " (a different camera or model)");
  const int C = src.format == PixelFormat::kRgb8 ? 3 : 1;
  HOVS_REQUIRE(src.stride >= size_t(src.width) * C, "remap input", "row stride ", src.stride,
               " is smaller than a row of ", src.width * C, " bytes");
  HOVS_REQUIRE(src.format != PixelFormat::kBayerRggb8 || (src.width % 2 == 0 && src.height % 2 == 0), "remap input",
               "a Bayer mosaic needs an even width and height");
  const auto start = std::chrono::steady_clock::now();
  pyramid_.resize(std::max(0, table_.levels - 1));
  for (size_t l = 0; l < pyramid_.size(); ++l) DownsampleHalf(l == 0 ? src : LevelView(pyramid_[l - 1]), &pyramid_[l]);
  pyramid_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void Remapper::RemapRows(const ImageView& src, Interpolation interp, int view, int tile_row, Image8* out) const {
  const ViewTable& vt = table_.views[view];
  const int T = vt.tile;
  const int v0 = tile_row * T, nv = std::min(T, vt.view.height - v0);
  const int OC = out->channels;
  const size_t ostride = size_t(out->width) * OC;
  // The band of nv rows is written into a per-thread buffer (it stays in this core's cache), then streamed out
  // to the view with non-temporal stores (see StreamCopy).
  thread_local std::vector<uint8_t> band_buffer;
  band_buffer.resize(size_t(nv) * ostride);
  uint8_t* band = band_buffer.data();
  for (int tx = 0; tx < vt.tiles_x; ++tx) {
    const Tile& t = vt.tiles[tile_row * vt.tiles_x + tx];
    // The source regions of the next tiles: the remap's reads follow curves the hardware prefetchers do not
    // predict. Two tiles ahead measured best (article's six views: 1.9-2.1x -> 2.1-2.7x cv::remap in one
    // comparison of distances 0-4).
    if (tx == 0)
      for (int d = 1; d < kPrefetchTiles && d < vt.tiles_x; ++d)
        PrefetchTile(src, pyramid_, vt.tiles[tile_row * vt.tiles_x + d]);
    if (tx + kPrefetchTiles < vt.tiles_x)
      PrefetchTile(src, pyramid_, vt.tiles[tile_row * vt.tiles_x + tx + kPrefetchTiles]);
    const int u0 = tx * T, nu = std::min(T, vt.view.width - u0);
    uint8_t* base = band + size_t(u0) * OC;
    if (t.kind == TileKind::kEmpty) {
      for (int j = 0; j < nv; ++j) std::memset(base + j * ostride, 0, size_t(nu) * OC);
      continue;
    }
    // The image this tile samples.
    const ImageView im = TileSource(src, pyramid_, t);
    const uint8_t* data = im.data;
    const int w = im.width, h = im.height;
    const ptrdiff_t stride = static_cast<ptrdiff_t>(im.stride);
    const PixelFormat fmt = im.format;
    const bool fast = t.inside && interp != Interpolation::kBicubic;
    if (fast && interp == Interpolation::kBilinear) {
      if (fmt == PixelFormat::kGray8) {
        WalkTile<1>(vt, t, T, nu, nv, base, ostride,
                    FastRow{kernels::BilinearGrayRow, kernels::BilinearGrayTile, data, stride});
      } else if (fmt == PixelFormat::kRgb8) {
        WalkTile<3>(vt, t, T, nu, nv, base, ostride,
                    FastRow{kernels::BilinearRgbRow, kernels::BilinearRgbTile, data, stride});
      } else {
        WalkTile<3>(vt, t, T, nu, nv, base, ostride,
                    FastRow{kernels::BayerRgbRow, kernels::BayerRgbTile, data, stride});
      }
      continue;
    }
    if (fast && fmt == PixelFormat::kGray8) {
      WalkTile<1>(vt, t, T, nu, nv, base, ostride, PerPixel<NearestSampler<1>, 1>{{data, stride}});
      continue;
    }
    if (fast && fmt == PixelFormat::kRgb8) {
      WalkTile<3>(vt, t, T, nu, nv, base, ostride, PerPixel<NearestSampler<3>, 3>{{data, stride}});
      continue;
    }
    GenericSampler g;
    g.m = interp;
    if (fmt == PixelFormat::kBayerRggb8) {
      g.bayer = true;
      g.num_planes = 4;
      const int hw = w / 2, hh = h / 2;
      g.planes[0] = {data, hw, hh, 2, 2 * stride};
      g.planes[1] = {data + 1, hw, hh, 2, 2 * stride};
      g.planes[2] = {data + stride, hw, hh, 2, 2 * stride};
      g.planes[3] = {data + stride + 1, hw, hh, 2, 2 * stride};
    } else {
      const int C = fmt == PixelFormat::kRgb8 ? 3 : 1;
      g.num_planes = C;
      for (int c = 0; c < C; ++c) g.planes[c] = {data + c, w, h, C, stride};
    }
    if (OC == 1) {
      WalkTile<1>(vt, t, T, nu, nv, base, ostride, PerPixel<GenericSampler, 1>{g});
    } else {
      WalkTile<3>(vt, t, T, nu, nv, base, ostride, PerPixel<GenericSampler, 3>{g});
    }
  }
  StreamCopy(band, size_t(nv) * ostride, out->data.data() + size_t(v0) * ostride);
}

void Remapper::Run(const ImageView& src, Interpolation interp, std::vector<Image8>* outputs) {
  Prepare(src);
  const int n = static_cast<int>(table_.views.size());
  outputs->resize(n);
  const int OC = src.format == PixelFormat::kGray8 ? 1 : 3;
  std::vector<std::pair<int, int>> rows;  // (view, tile row)
  for (int v = 0; v < n; ++v) {
    Image8& o = (*outputs)[v];
    const auto& vw = table_.views[v].view;
    if (o.width != vw.width || o.height != vw.height || o.channels != OC) {
      o.width = vw.width, o.height = vw.height, o.channels = OC;
      o.data.resize(size_t(o.width) * o.height * OC);
    }
    for (int r = 0; r < table_.views[v].tiles_y; ++r) rows.emplace_back(v, r);
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rows.size(), 1), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t k = range.begin(); k < range.end(); ++k)
      RemapRows(src, interp, rows[k].first, rows[k].second, &(*outputs)[rows[k].first]);
  });
}

void RunRemappers(const std::vector<RemapJob>& jobs, Interpolation interp) {
  struct Row {
    const RemapJob* job;
    int view, tile_row;
  };
  std::vector<Row> rows;
  for (const RemapJob& j : jobs) {
    const RemapTable& t = j.remapper->table_;
    HOVS_REQUIRE(j.outputs.size() == t.views.size(), "remap", "a job with ", j.outputs.size(), " outputs for ",
                 t.views.size(), " views");
    j.remapper->Prepare(j.src);
    const int OC = j.src.format == PixelFormat::kGray8 ? 1 : 3;
    for (size_t v = 0; v < t.views.size(); ++v) {
      Image8& o = *j.outputs[v];
      const auto& vw = t.views[v].view;
      if (o.width != vw.width || o.height != vw.height || o.channels != OC) {
        o.width = vw.width, o.height = vw.height, o.channels = OC;
        o.data.resize(size_t(o.width) * o.height * OC);
      }
      for (int r = 0; r < t.views[v].tiles_y; ++r) rows.push_back({&j, static_cast<int>(v), r});
    }
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rows.size(), 1), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t k = range.begin(); k < range.end(); ++k) {
      const Row& r = rows[k];
      r.job->remapper->RemapRows(r.job->src, interp, r.view, r.tile_row, r.job->outputs[r.view]);
    }
  });
}

void Remapper::RunView(const ImageView& src, Interpolation interp, int view, Image8* out) {
  HOVS_REQUIRE(view >= 0 && view < int(table_.views.size()), "remap", "no view ", view);
  Prepare(src);
  const auto& vw = table_.views[view].view;
  out->width = vw.width, out->height = vw.height, out->channels = src.format == PixelFormat::kGray8 ? 1 : 3;
  out->data.resize(size_t(out->width) * out->height * out->channels);
  tbb::parallel_for(0, table_.views[view].tiles_y, [&](int r) { RemapRows(src, interp, view, r, out); });
}

}  // namespace hovs::unwrap
