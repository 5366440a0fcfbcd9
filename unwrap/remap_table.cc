#include "unwrap/remap_table.h"

#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <optional>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "core/large_pages.h"

namespace hovs::unwrap {
namespace {

constexpr char kMagic[8] = {'H', 'O', 'V', 'S', 'M', 'A', 'P', '\0'};
constexpr uint32_t kFormatVersion = 2;
constexpr uint32_t kOldestReadableVersion = 1;  // one tile size for every view

bool IsTileSize(int t) { return t == 8 || t == 16 || t == 32 || t == 64; }

int32_t ToFixed(double v) { return static_cast<int32_t>(std::llround(v * 65536.0)); }
double FromFixed(int32_t v) { return v / 65536.0; }
inline double Sq(double v) { return v * v; }

// Level-L coordinate of a level-0 coordinate.
double AtLevel(double x, int level) { return level == 0 ? x : (x + 0.5) / double(1 << level) - 0.5; }

// The size of pyramid level L of an n-pixel side, as the remap makes it (DownsampleHalf rounds up).
int LevelSide(int n, int level) {
  for (int l = 0; l < level; ++l) n = (n + 1) / 2;
  return n;
}

// The 16.16 coordinates of the tile's pixels i < nu, j < nv exactly as the kernels compute them (interp: the row
// polynomials in float, RowPoly; dense: as stored), each given to f(x, y); invalid dense pixels are skipped. An
// interp coordinate that float arithmetic cannot take to int32 (non-finite, or beyond +-2^30 px / 65536) is
// passed as kInvalidCoordinate with *overflow set, never converted (the conversion would be undefined).
template <class F>
void ForEachTileCoordinate(const Tile& t, const int32_t* dense, int T, int nu, int nv, bool* overflow, F f) {
  constexpr float kLimit = 1073741824.f;  // 2^30
  for (int j = 0; j < nv; ++j) {
    if (t.kind == TileKind::kInterp) {
      const RowPoly p = InterpRowPoly(t, T, j);
      for (int i = 0; i < nu; ++i) {
        const float fi = float(i);
        const float fx = p.bx + fi * (p.c1x + fi * p.c2x), fy = p.by + fi * (p.c1y + fi * p.c2y);
        if (!(std::abs(fx) < kLimit && std::abs(fy) < kLimit)) {
          *overflow = true;
          f(kInvalidCoordinate, kInvalidCoordinate);
          continue;
        }
        f(p.X(i), p.Y(i));
      }
    } else {
      for (int i = 0; i < nu; ++i) {
        const int32_t* d = dense + 2 * (j * T + i);
        if (d[0] != kInvalidCoordinate) f(d[0], d[1]);
      }
    }
  }
}

// Whether every coordinate the kernels read for the tile lies at least 2 px inside its level's lw x lh image
// (x, y in [2, lw - 4]): the tile may then use the kernels that read without clamping (Tile::inside). The
// builder sets the flag from this and the loader checks it, so a mapping file cannot make them read outside
// the frame.
bool TileInside(const Tile& t, const int32_t* dense, int T, int nu, int nv, int lw, int lh) {
  const int64_t lo = int64_t(2) << 16, hx = int64_t(lw - 4) << 16, hy = int64_t(lh - 4) << 16;
  bool inside = lw >= 6 && lh >= 6, overflow = false;
  ForEachTileCoordinate(t, dense, T, nu, nv, &overflow,
                        [&](int32_t x, int32_t y) { inside = inside && x >= lo && y >= lo && x <= hx && y <= hy; });
  return inside && !overflow;
}

uint64_t Fnv1a(const char* data, size_t n, uint64_t h = 1469598103934665603ull) {
  for (size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= 1099511628211ull;
  }
  return h;
}

template <class T>
void Put(std::string* s, const T& v) {
  s->append(reinterpret_cast<const char*>(&v), sizeof(T));
}

class Reader {
 public:
  Reader(const std::string& data, std::string where) : d_(data), where_(std::move(where)) {}
  template <class T>
  T Get(const char* what) {
    T v;
    Bytes(&v, sizeof(T), what);
    return v;
  }
  void Bytes(void* out, size_t n, const char* what) {
    HOVS_REQUIRE(pos_ + n <= d_.size(), where_, "truncated mapping file (reading ", what, ")");
    if (n > 0) std::memcpy(out, d_.data() + pos_, n);  // an empty table's data() may be null
    pos_ += n;
  }
  size_t pos() const { return pos_; }

 private:
  const std::string& d_;
  std::string where_;
  size_t pos_ = 0;
};

nlohmann::json SpecJson(const ViewSpec& v) {
  nlohmann::json j = {{"name", v.name}, {"type", ToString(v.type)}, {"width", v.width}, {"height", v.height}};
  if (v.type == ViewProjection::kPerspective) {
    j["yaw_deg"] = v.yaw_deg, j["pitch_deg"] = v.pitch_deg, j["roll_deg"] = v.roll_deg, j["hfov_deg"] = v.hfov_deg;
  } else {
    j["elevation_min_deg"] = v.elevation_min_deg, j["elevation_max_deg"] = v.elevation_max_deg;
    j["azimuth_centre_deg"] = v.azimuth_centre_deg, j["azimuth_span_deg"] = v.azimuth_span_deg;
    j["pole"] = {v.pole.w(), v.pole.x(), v.pole.y(), v.pole.z()};
  }
  return j;
}

ViewSpec SpecFromJson(const nlohmann::json& j, const std::string& where) {
  ViewSpec v;
  v.name = j.at("name");
  const std::string t = j.at("type");
  HOVS_REQUIRE(t == "perspective" || t == "cylindrical" || t == "epipolar" || t == "longlat", where,
               "unknown view type '", t, "'");
  v.type = t == "perspective"   ? ViewProjection::kPerspective
           : t == "cylindrical" ? ViewProjection::kCylindrical
           : t == "epipolar"    ? ViewProjection::kEpipolar
                                : ViewProjection::kLongLat;
  v.width = j.at("width"), v.height = j.at("height");
  if (v.type == ViewProjection::kPerspective) {
    v.yaw_deg = j.at("yaw_deg"), v.pitch_deg = j.at("pitch_deg"), v.roll_deg = j.at("roll_deg");
    v.hfov_deg = j.at("hfov_deg");
  } else {
    v.elevation_min_deg = j.at("elevation_min_deg"), v.elevation_max_deg = j.at("elevation_max_deg");
    v.azimuth_centre_deg = j.at("azimuth_centre_deg"), v.azimuth_span_deg = j.at("azimuth_span_deg");
    if (j.contains("pole")) v.pole = Eigen::Quaterniond(j["pole"][0], j["pole"][1], j["pole"][2], j["pole"][3]);
  }
  return v;
}

// Builds one tile: exact coordinates at every pixel, then the cheapest exact-enough representation.
struct TileBuild {
  Tile tile;
  std::vector<int32_t> dense;
  int valid = 0;
  double interp_error = 0;
};

TileBuild BuildTile(const AnyModel& model, const VirtualView<double>& view, int T, int tx, int ty,
                    const RemapOptions& o) {
  const int u0 = tx * T, v0 = ty * T;
  const int nu = std::min(T, view.width - u0), nv = std::min(T, view.height - v0);
  TileBuild b;
  std::vector<double> xs(T * T, 0), ys(T * T, 0);
  std::vector<char> ok(T * T, 0);
  const auto exact = [&](double u, double v, double* x, double* y) {
    Vec3d bearing;
    Vec2d src;
    if (!view.MirrorFromImg(Vec2d(u, v), &bearing) || !model.ImgFromMirror(bearing, &src)) return false;
    *x = src(0), *y = src(1);
    return true;
  };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int k = j * T + i;
      ok[k] = exact(u0 + i, v0 + j, &xs[k], &ys[k]);
      b.valid += ok[k];
    }
  if (b.valid == 0) return b;  // empty

  // Minification: source pixels per output pixel, from finite differences across the tile.
  double scale = 0;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int k = j * T + i;
      if (!ok[k]) continue;
      if (i + 1 < nu && ok[k + 1]) scale = std::max(scale, std::sqrt(Sq(xs[k + 1] - xs[k]) + Sq(ys[k + 1] - ys[k])));
      if (j + 1 < nv && ok[k + T]) scale = std::max(scale, std::sqrt(Sq(xs[k + T] - xs[k]) + Sq(ys[k + T] - ys[k])));
    }
  int level = 0;
  if (o.antialias && scale >= 2) level = std::min(o.max_level, static_cast<int>(std::floor(std::log2(scale))));
  b.tile.level = static_cast<uint8_t>(level);
  const double lw = std::ceil(model.width() / double(1 << level)), lh = std::ceil(model.height() / double(1 << level));

  // Biquadratic interpolation through the 3 x 3 nodes, checked at every pixel as the kernels evaluate it.
  Tile& tl = b.tile;
  bool nodes = b.valid == nu * nv;
  for (int k = 0; k < 9 && nodes; ++k) {
    double x = 0, y = 0;
    nodes = exact(u0 + (k % 3) * T / 2, v0 + (k / 3) * T / 2, &x, &y);
    tl.x[k] = static_cast<float>(AtLevel(x, level));
    tl.y[k] = static_cast<float>(AtLevel(y, level));
  }
  bool interp = false;
  if (nodes) {
    double worst = 0;
    std::vector<int32_t> rx(T), ry(T);
    const double level_scale = double(1 << level);
    for (int j = 0; j < nv; ++j) {
      InterpRow(tl, T, j, rx.data(), ry.data());
      for (int i = 0; i < nu; ++i) {
        const double x = (FromFixed(rx[i]) + 0.5) * level_scale - 0.5, y = (FromFixed(ry[i]) + 0.5) * level_scale - 0.5;
        worst = std::max(worst, std::sqrt(Sq(x - xs[j * T + i]) + Sq(y - ys[j * T + i])));
      }
    }
    interp = worst <= o.max_interp_error;
    if (interp) b.interp_error = worst;
  }
  if (interp) {
    // Nodes may lie outside the view (partial edge tiles); the pixels that exist are what was checked.
    b.tile.kind = TileKind::kInterp;
    b.tile.inside = TileInside(b.tile, nullptr, T, nu, nv, int(lw), int(lh)) ? 1 : 0;
    return b;
  }
  std::fill(tl.x, tl.x + 9, 0.f);
  std::fill(tl.y, tl.y + 9, 0.f);
  b.tile.kind = TileKind::kDense;
  b.dense.assign(2 * T * T, kInvalidCoordinate);
  for (int k = 0; k < T * T; ++k) {
    if (!ok[k]) continue;
    b.dense[2 * k] = ToFixed(AtLevel(xs[k], level));
    b.dense[2 * k + 1] = ToFixed(AtLevel(ys[k], level));
  }
  b.tile.inside = TileInside(b.tile, b.dense.data(), T, nu, nv, int(lw), int(lh)) ? 1 : 0;
  return b;
}

nlohmann::json ModelJson(const AnyModel& model) {
  nlohmann::json p = nlohmann::json::object();
  for (const auto& [k, v] : model.Parameters()) p[k] = v;
  return {{"kind", model.KindName()}, {"parameters", p}};
}

}  // namespace

void RemapOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(tile == 0 || IsTileSize(tile), where, "tile must be 8, 16, 32 or 64, or 0 for automatic (got ", tile,
               ")");
  HOVS_REQUIRE(max_interp_error > 0 && max_interp_error <= 0.5, where, "max_interp_error must be in (0, 0.5] px (got ",
               max_interp_error, ")");
  HOVS_REQUIRE(max_level >= 0 && max_level <= 8, where, "max_level must be 0..8");
}

void ExactMaps(const AnyModel& model, const VirtualView<double>& view, std::vector<float>* map_x,
               std::vector<float>* map_y) {
  map_x->assign(size_t(view.width) * view.height, -1.f);
  map_y->assign(size_t(view.width) * view.height, -1.f);
  tbb::parallel_for(0, view.height, [&](int v) {
    for (int u = 0; u < view.width; ++u) {
      Vec3d b;
      Vec2d s;
      if (!view.MirrorFromImg(Vec2d(u, v), &b) || !model.ImgFromMirror(b, &s)) continue;
      (*map_x)[size_t(v) * view.width + u] = static_cast<float>(s(0));
      (*map_y)[size_t(v) * view.width + u] = static_cast<float>(s(1));
    }
  });
}

void RemapTable::DecodeView(int index, std::vector<float>* map_x, std::vector<float>* map_y) const {
  const ViewTable& vt = views.at(index);
  const int W = vt.view.width, H = vt.view.height, T = vt.tile;
  map_x->assign(size_t(W) * H, -1.f);
  map_y->assign(size_t(W) * H, -1.f);
  for (int ty = 0; ty < vt.tiles_y; ++ty)
    for (int tx = 0; tx < vt.tiles_x; ++tx) {
      const Tile& t = vt.tiles[ty * vt.tiles_x + tx];
      if (t.kind == TileKind::kEmpty) continue;
      const double scale = double(1 << t.level);
      for (int j = 0; j < T && ty * T + j < H; ++j)
        for (int i = 0; i < T && tx * T + i < W; ++i) {
          double x = 0, y = 0;
          if (t.kind == TileKind::kInterp) {
            int32_t rx[64], ry[64];
            InterpRow(t, T, j, rx, ry);
            x = FromFixed(rx[i]);
            y = FromFixed(ry[i]);
          } else {
            const int32_t* d = &vt.dense[t.dense_index * 2 + 2 * (j * T + i)];
            if (d[0] == kInvalidCoordinate) continue;
            x = FromFixed(d[0]), y = FromFixed(d[1]);
          }
          (*map_x)[size_t(ty * T + j) * W + tx * T + i] = static_cast<float>((x + 0.5) * scale - 0.5);
          (*map_y)[size_t(ty * T + j) * W + tx * T + i] = static_cast<float>((y + 0.5) * scale - 0.5);
        }
    }
}

namespace {
// Whether a tile may stay in a view built with RemapOptions::tile = 0 at 64 pixels.
bool FitsLargeTiles(const Tile& t) {
  return t.kind == TileKind::kEmpty || (t.kind == TileKind::kInterp && t.level == 0 && t.inside);
}

// One view's table at tile size T. With `only_if_large_fits`, nullopt as soon as a tile does not fit (the
// remaining tiles are skipped; the answer does not depend on which thread finds it first).
std::optional<ViewTable> BuildView(const AnyModel& model, const ViewSpec& spec, int T, const RemapOptions& options,
                                   bool only_if_large_fits) {
  ViewTable vt;
  vt.spec = spec;
  vt.view = spec.View();
  vt.tile = T;
  vt.tiles_x = (vt.view.width + T - 1) / T;
  vt.tiles_y = (vt.view.height + T - 1) / T;
  const int n = vt.tiles_x * vt.tiles_y;
  std::vector<TileBuild> built(n);
  std::atomic<bool> misfit{false};
  tbb::parallel_for(0, n, [&](int k) {
    if (misfit.load(std::memory_order_relaxed)) return;
    built[k] = BuildTile(model, vt.view, T, k % vt.tiles_x, k / vt.tiles_x, options);
    if (only_if_large_fits && !FitsLargeTiles(built[k].tile)) misfit = true;
  });
  if (misfit) return std::nullopt;
  vt.tiles.resize(n);
  for (int k = 0; k < n; ++k) {
    Tile t = built[k].tile;
    vt.valid_pixels += built[k].valid;
    if (t.kind == TileKind::kDense) {
      t.dense_index = static_cast<uint32_t>(vt.dense.size() / 2);
      vt.dense.insert(vt.dense.end(), built[k].dense.begin(), built[k].dense.end());
      ++vt.dense_tiles;
    } else if (t.kind == TileKind::kInterp) {
      ++vt.interp_tiles;
      vt.max_interp_error = std::max(vt.max_interp_error, built[k].interp_error);
    } else {
      ++vt.empty_tiles;
    }
    if (t.kind != TileKind::kEmpty) vt.max_level = std::max<int>(vt.max_level, t.level);
    vt.tiles[k] = t;
  }
  return vt;
}
}  // namespace

RemapTable BuildRemapTable(const AnyModel& model, const Layout& layout, const RemapOptions& options,
                           const std::string& versions_json) {
  options.Check("remap options");
  layout.Check("layout " + layout.name);
  // Every caller (the commands, the export, the Python module) meets the same memory check before a table of
  // views larger than the memory left is built.
  CheckViewsMemory("layout " + layout.name, layout.views, AvailableMemoryBytes());
  const auto start = std::chrono::steady_clock::now();
  RemapTable table;
  table.source_width = model.width(), table.source_height = model.height();
  HOVS_REQUIRE(table.source_width <= kMaxSourceSide && table.source_height <= kMaxSourceSide, "remap table",
               "the model's image is ", table.source_width, " x ", table.source_height, "; remap tables take at most ",
               kMaxSourceSide, " pixels a side (16.16 fixed-point coordinates)");
  for (const auto& spec : layout.views) {
    std::optional<ViewTable> vt;
    if (options.tile == 0) vt = BuildView(model, spec, 64, options, /*only_if_large_fits=*/true);
    if (!vt) vt = BuildView(model, spec, options.tile != 0 ? options.tile : 32, options, false);
    table.levels = std::max(table.levels, vt->max_level + 1);
    table.views.push_back(std::move(*vt));
  }
  nlohmann::json views = nlohmann::json::array();
  for (const auto& v : layout.views) views.push_back(SpecJson(v));
  nlohmann::json versions = nlohmann::json::parse(versions_json, nullptr, false);
  if (versions.is_discarded()) versions = nlohmann::json::object();
  const nlohmann::json header = {{"format", "hovs-mapping"},
                                 {"format_version", kFormatVersion},
                                 {"byte_order", "little"},
                                 {"model", ModelJson(model)},
                                 {"layout", {{"name", layout.name}, {"views", views}}},
                                 {"source", {{"width", model.width()}, {"height", model.height()}}},
                                 {"options",
                                  {{"tile", options.tile},
                                   {"max_interp_error_px", options.max_interp_error},
                                   {"antialias", options.antialias},
                                   {"max_level", options.max_level}}},
                                 {"versions", versions}};
  table.header = header.dump(1);
  table.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return table;
}

void SaveRemapTable(const std::filesystem::path& path, const RemapTable& table) {
  CheckOutputFile(path, std::string(kMagic, sizeof kMagic), "a hovs mapping file");
  WriteFileAtomic(path, SerializeRemapTable(table));
}

uint64_t MappingChecksum(const char* data, size_t size) { return Fnv1a(data, size); }

std::string SerializeRemapTable(const RemapTable& table) {
  std::string s(kMagic, sizeof kMagic);
  Put(&s, kFormatVersion);
  Put(&s, static_cast<uint32_t>(table.header.size()));
  s += table.header;
  Put(&s, static_cast<uint32_t>(table.views.size()));
  for (const auto& v : table.views) {
    Put(&s, static_cast<uint32_t>(v.tiles_x));
    Put(&s, static_cast<uint32_t>(v.tiles_y));
    Put(&s, static_cast<uint32_t>(v.tile));
    Put(&s, static_cast<uint32_t>(v.tiles.size()));
    s.append(reinterpret_cast<const char*>(v.tiles.data()), v.tiles.size() * sizeof(Tile));
    Put(&s, static_cast<uint64_t>(v.dense.size()));
    s.append(reinterpret_cast<const char*>(v.dense.data()), v.dense.size() * sizeof(int32_t));
  }
  Put(&s, Fnv1a(s.data(), s.size()));
  return s;
}

namespace {
std::string CheckedContents(const std::string& where, const std::string& data) {
  HOVS_REQUIRE(data.size() >= sizeof kMagic + 16 && std::memcmp(data.data(), kMagic, sizeof kMagic) == 0, where,
               "not a hovs mapping file (bad magic)");
  uint32_t version = 0;
  std::memcpy(&version, data.data() + sizeof kMagic, 4);
  HOVS_REQUIRE(version >= kOldestReadableVersion && version <= kFormatVersion, where, "mapping file format version ",
               version, " is not supported (this hovs reads versions ", kOldestReadableVersion, " to ", kFormatVersion,
               "); rebuild the mapping");
  uint64_t stored = 0;
  std::memcpy(&stored, data.data() + data.size() - 8, 8);
  const uint64_t actual = Fnv1a(data.data(), data.size() - 8);
  HOVS_REQUIRE(stored == actual, where, "checksum mismatch: the mapping file is corrupt or truncated; rebuild it");
  return data.substr(0, data.size() - 8);
}
}  // namespace

std::string MappingFileHeader(const std::filesystem::path& path) {
  const std::string body = CheckedContents(path.string(), ReadFile(path));
  Reader r(body, path.string());
  char magic[8];
  r.Bytes(magic, 8, "magic");
  r.Get<uint32_t>("version");
  const uint32_t n = r.Get<uint32_t>("header length");
  std::string header(n, '\0');
  r.Bytes(header.data(), n, "header");
  return header;
}

namespace {

// The checks of one loaded view's tiles against the header (where: the file and the view). A damaged or edited
// file with a valid checksum must not make the remap read outside its source image: every tile's kind, level and
// dense range are checked, every interp tile's coordinates are evaluated as the kernels evaluate them, and the
// flag that selects the unclamped kernels is accepted only where TileInside holds.
void CheckViewTiles(const ViewTable& v, int source_width, int source_height, const std::string& where) {
  const int T = v.tile, W = v.view.width, H = v.view.height;
  for (int ty = 0; ty < v.tiles_y; ++ty)
    for (int tx = 0; tx < v.tiles_x; ++tx) {
      const Tile& t = v.tiles[size_t(ty) * v.tiles_x + tx];
      const std::string tile = where + ", tile (" + std::to_string(tx) + ", " + std::to_string(ty) + ")";
      HOVS_REQUIRE(t.kind == TileKind::kEmpty || t.kind == TileKind::kInterp || t.kind == TileKind::kDense, tile,
                   "bad tile kind ", int(t.kind));
      if (t.kind == TileKind::kEmpty) continue;
      HOVS_REQUIRE(t.level <= 8, tile, "bad pyramid level ", int(t.level));
      HOVS_REQUIRE(t.inside <= 1, tile, "bad inside flag ", int(t.inside));
      if (t.kind == TileKind::kDense)
        HOVS_REQUIRE((uint64_t(t.dense_index) + uint64_t(T) * T) * 2 <= v.dense.size(), tile,
                     "dense tile index out of range");
      if (t.kind == TileKind::kInterp)
        for (int k = 0; k < 9; ++k)
          HOVS_REQUIRE(std::isfinite(t.x[k]) && std::isfinite(t.y[k]), tile, "a node coordinate is not finite");
      const int lw = LevelSide(source_width, t.level), lh = LevelSide(source_height, t.level);
      const int nu = std::min(T, W - tx * T), nv = std::min(T, H - ty * T);
      const int32_t* dense = t.kind == TileKind::kDense ? v.dense.data() + size_t(t.dense_index) * 2 : nullptr;
      bool overflow = false;
      ForEachTileCoordinate(t, dense, T, nu, nv, &overflow, [](int32_t, int32_t) {});
      HOVS_REQUIRE(!overflow, tile, "coordinates beyond the fixed-point range");
      HOVS_REQUIRE(!t.inside || TileInside(t, dense, T, nu, nv, lw, lh), tile,
                   "marked to be read without clamping but samples outside its source image (", lw, " x ", lh,
                   " at level ", int(t.level), "): the mapping file was damaged or edited; rebuild it");
    }
}

}  // namespace

RemapTable LoadRemapTable(const std::filesystem::path& path) { return ParseRemapTable(ReadFile(path), path.string()); }

RemapTable ParseRemapTable(const std::string& bytes, const std::string& where) {
  const std::string body = CheckedContents(where, bytes);
  Reader r(body, where);
  char magic[8];
  r.Bytes(magic, 8, "magic");
  r.Get<uint32_t>("version");
  const uint32_t hn = r.Get<uint32_t>("header length");
  HOVS_REQUIRE(hn <= body.size() - r.pos(), where, "truncated mapping file (header)");
  RemapTable t;
  t.header.resize(hn);
  r.Bytes(t.header.data(), hn, "header");
  const auto h = ParseJson(t.header, where + " (header)");
  HOVS_REQUIRE(h.is_object() && JsonText(h, "format") == "hovs-mapping", where,
               "the header is not a hovs mapping header");
  HOVS_REQUIRE(JsonText(h, "byte_order") == "little", where, "unsupported byte order");
  try {
    t.source_width = h.at("source").at("width");
    t.source_height = h.at("source").at("height");
    HOVS_REQUIRE(t.source_width >= 1 && t.source_height >= 1 && t.source_width <= kMaxSourceSide &&
                     t.source_height <= kMaxSourceSide,
                 where, "source image size ", t.source_width, " x ", t.source_height, " is outside 1..",
                 kMaxSourceSide);
    const int header_tile = h.at("options").at("tile");  // 0: chosen per view
    const auto& views = h.at("layout").at("views");
    HOVS_REQUIRE(views.is_array() && !views.empty() && views.size() <= 256, where, "the header lists ",
                 views.is_array() ? views.size() : 0, " views (1 to 256)");
    const uint32_t nviews = r.Get<uint32_t>("view count");
    HOVS_REQUIRE(nviews == views.size(), where, "view count does not match the header");
    std::vector<ViewSpec> specs;
    for (uint32_t i = 0; i < nviews; ++i) {
      ViewTable v;
      v.spec = SpecFromJson(views[i], where);
      v.spec.Check(where);
      specs.push_back(v.spec);
      CheckViewsMemory(where, specs, AvailableMemoryBytes());
      v.view = v.spec.View();
      const std::string vw = where + " (view '" + v.spec.name + "')";
      v.tiles_x = static_cast<int>(r.Get<uint32_t>("tiles_x"));
      v.tiles_y = static_cast<int>(r.Get<uint32_t>("tiles_y"));
      const uint32_t tile = r.Get<uint32_t>("tile size");
      const uint32_t count = r.Get<uint32_t>("tile count");
      HOVS_REQUIRE(IsTileSize(int(tile)) && (header_tile == 0 || int(tile) == header_tile), vw, "tile size ", tile,
                   " (the header asks for ", header_tile, ")");
      v.tile = static_cast<int>(tile);
      HOVS_REQUIRE(v.tiles_x == (v.view.width + v.tile - 1) / v.tile &&
                       v.tiles_y == (v.view.height + v.tile - 1) / v.tile && count == uint32_t(v.tiles_x * v.tiles_y),
                   vw, "the tile grid does not match the view's size");
      HOVS_REQUIRE(uint64_t(count) * sizeof(Tile) <= body.size() - r.pos(), vw, "truncated mapping file (tiles)");
      v.tiles.resize(count);
      r.Bytes(v.tiles.data(), count * sizeof(Tile), "tiles");
      const uint64_t nd = r.Get<uint64_t>("dense count");
      HOVS_REQUIRE(nd % (2ull * v.tile * v.tile) == 0 && nd <= (body.size() - r.pos()) / 4, vw, "bad dense table size");
      v.dense.resize(nd);
      r.Bytes(v.dense.data(), nd * sizeof(int32_t), "dense coordinates");
      CheckViewTiles(v, t.source_width, t.source_height, vw);
      for (const Tile& tl : v.tiles) {
        if (tl.kind == TileKind::kEmpty) {
          ++v.empty_tiles;
        } else {
          tl.kind == TileKind::kDense ? ++v.dense_tiles : ++v.interp_tiles;
          v.max_level = std::max<int>(v.max_level, tl.level);
        }
      }
      t.levels = std::max(t.levels, v.max_level + 1);
      t.views.push_back(std::move(v));
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(where, std::string("the header misses a field or has one of the wrong type: ") + e.what());
  }
  HOVS_REQUIRE(r.pos() == body.size(), where, "trailing bytes after the last view");
  return t;
}

}  // namespace hovs::unwrap
