// Unwrap without rendering: view geometry round trips, tables against the exact model, mapping files (round
// trip, corruption, version), kernels (AVX2 = scalar, ramps reproduced, Bayer = RGB on grey-world content),
// bad input.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>

#include "core/error.h"
#include "core/model_fit.h"
#include "unwrap/remap.h"
#include "unwrap/remap_kernels.h"
#include "tests/core/test_rigs.h"

namespace hovs::unwrap {
namespace {

constexpr double kDeg = M_PI / 180;

CatadioptricCamera<double> Rig() { return test::AlignedRig(); }

std::filesystem::path TempDir() {
  const auto d = std::filesystem::temp_directory_path() /
                 ("hovs_unwrap_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::create_directories(d);
  return d;
}

TEST(VirtualView, PerspectiveAndPanoramaRoundTrip) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0, 1);
  const std::vector<VirtualView<double>> views = {
      VirtualView<double>::Perspective(1200, 700, 65 * kDeg, 40 * kDeg, -30 * kDeg, 5 * kDeg),
      VirtualView<double>::Panorama(ViewProjection::kCylindrical, 3600, 900, -75 * kDeg, -2 * kDeg),
      VirtualView<double>::Panorama(ViewProjection::kLongLat, 2000, 1000, -90 * kDeg, 90 * kDeg, 30 * kDeg)};
  for (const auto& v : views) {
    double worst = 0;
    for (int k = 0; k < 2000; ++k) {
      const Vec2d uv(-0.49 + U(rng) * (v.width - 0.02), -0.49 + U(rng) * (v.height - 0.02));
      Vec3d b;
      ASSERT_TRUE(v.MirrorFromImg(uv, &b));
      EXPECT_NEAR(b.norm(), 1.0, 1e-12);
      Vec2d back;
      ASSERT_TRUE(v.ImgFromMirror(b * 3.7, &back));
      worst = std::max(worst, (back - uv).norm());
    }
    EXPECT_LT(worst, 1e-8) << ToString(v.projection);
  }
}

TEST(VirtualView, PerspectiveLooksWhereYawAndPitchSayAndIsUpright) {
  const auto v = VirtualView<double>::Perspective(1201, 701, 60 * kDeg, 60 * kDeg, -30 * kDeg, 0);
  Vec3d b;
  ASSERT_TRUE(v.MirrorFromImg(Vec2d(600, 350), &b));  // the principal point
  EXPECT_NEAR(std::atan2(b.y(), b.x()), 60 * kDeg, 1e-12);
  EXPECT_NEAR(std::asin(b.z()), -30 * kDeg, 1e-12);
  Vec3d up, right;
  ASSERT_TRUE(v.MirrorFromImg(Vec2d(600, 0), &up));
  ASSERT_TRUE(v.MirrorFromImg(Vec2d(1200, 350), &right));
  EXPECT_GT(up.z(), b.z());  // image rows go down in the world
  // Right of the image is clockwise seen from above (azimuth decreases), as for a person looking out.
  EXPECT_LT(std::atan2(right.y(), right.x()), 60 * kDeg);
}

TEST(VirtualView, PanoramaWrapsWithoutASeam) {
  const auto v = VirtualView<double>::Panorama(ViewProjection::kCylindrical, 3600, 900, -75 * kDeg, -2 * kDeg);
  // Column spacing is uniform across the wrap: the last column and the first are one column apart.
  Vec3d a, b;
  ASSERT_TRUE(v.MirrorFromImg(Vec2d(3599, 450), &a));
  ASSERT_TRUE(v.MirrorFromImg(Vec2d(0, 450), &b));
  Vec3d c, d;
  ASSERT_TRUE(v.MirrorFromImg(Vec2d(1000, 450), &c));
  ASSERT_TRUE(v.MirrorFromImg(Vec2d(1001, 450), &d));
  EXPECT_NEAR(std::acos(a.dot(b)), std::acos(c.dot(d)), 1e-9);
  Vec2d uv;
  ASSERT_TRUE(v.ImgFromMirror(b, &uv));
  EXPECT_NEAR(uv.x(), 0, 1e-9);
}

TEST(RemapTable, DecodedCoordinatesMatchTheExactModel) {
  const AnyModel exact = AnyModel::Exact(Rig());
  const AnyModel poly = AnyModel::Polynomial(PolynomialFromCatadioptric(Rig(), 5));
  Layout layout = PresetLayout("article");
  layout.views.resize(2);
  ViewSpec pano;
  pano.name = "pano", pano.type = ViewProjection::kCylindrical, pano.width = 1800, pano.height = 400;
  layout.views.push_back(pano);
  for (const AnyModel* m : {&exact, &poly}) {
    const RemapTable t = BuildRemapTable(*m, layout, {});
    ASSERT_EQ(t.views.size(), 3u);
    for (size_t v = 0; v < t.views.size(); ++v) {
      std::vector<float> ex, ey, dx, dy;
      ExactMaps(*m, t.views[v].view, &ex, &ey);
      t.DecodeView(static_cast<int>(v), &dx, &dy);
      double worst = 0;
      int64_t valid = 0, mismatch = 0;
      for (size_t k = 0; k < ex.size(); ++k) {
        if ((ex[k] < 0) != (dx[k] < 0)) ++mismatch;
        if (ex[k] < 0 || dx[k] < 0) continue;
        ++valid;
        worst = std::max(worst, std::hypot(double(ex[k]) - dx[k], double(ey[k]) - dy[k]));
      }
      EXPECT_EQ(mismatch, 0) << m->KindName() << " view " << v;
      EXPECT_GT(valid, int64_t(ex.size()) / 2);
      // 1/64 px interpolation tolerance plus float storage of 2750-pixel coordinates.
      EXPECT_LT(worst, 1.0 / 64 + 1e-3) << m->KindName() << " view " << v;
    }
  }
}

TEST(RemapTable, PanoramaHasInvalidPixelsWhereTheMirrorIsNotSeen) {
  Layout layout;
  layout.name = "wide";
  ViewSpec pano;
  pano.name = "pano", pano.type = ViewProjection::kLongLat, pano.width = 720, pano.height = 400;
  pano.elevation_min_deg = -89, pano.elevation_max_deg = 20;  // beyond both ends of the mirror's field
  layout.views.push_back(pano);
  const RemapTable t = BuildRemapTable(AnyModel::Exact(Rig()), layout, {});
  std::vector<float> x, y;
  t.DecodeView(0, &x, &y);
  EXPECT_LT(x[0], 0) << "top row (20 deg up) is above the mirror's field";
  EXPECT_LT(x[x.size() - 1], 0) << "bottom row (-89 deg) sees the camera";
  EXPECT_GE(x[200 * 720], 0) << "a middle row sees the mirror";
  EXPECT_GT(t.views[0].dense_tiles, 0);
  EXPECT_GT(t.views[0].empty_tiles, 0) << "the rows above the mirror's field";
}

TEST(RemapTable, MinifyingTilesSampleThePyramid) {
  Layout layout;
  layout.name = "small";
  ViewSpec pano;
  pano.name = "small", pano.type = ViewProjection::kCylindrical, pano.width = 360, pano.height = 120;
  layout.views.push_back(pano);
  const RemapTable t = BuildRemapTable(AnyModel::Exact(Rig()), layout, {});
  EXPECT_GE(t.views[0].max_level, 1);  // 1 degree per column: several source pixels at the rim
  EXPECT_EQ(t.levels, t.views[0].max_level + 1);
  RemapOptions no_aa;
  no_aa.antialias = false;
  EXPECT_EQ(BuildRemapTable(AnyModel::Exact(Rig()), layout, no_aa).levels, 1);
}

// The first n article views and a cylindrical panorama from 89 degrees down to 10 up, which crosses the rim and
// the camera's own reflection (dense and empty tiles; the automatic tile size keeps it at 32).
Layout ArticleAndRimPanorama(int n, int pano_width, int pano_height) {
  Layout layout = PresetLayout("article");
  layout.views.resize(n);
  ViewSpec pano;
  pano.name = "pano", pano.type = ViewProjection::kCylindrical, pano.width = pano_width, pano.height = pano_height;
  pano.elevation_min_deg = -89, pano.elevation_max_deg = 10;
  layout.views.push_back(pano);
  return layout;
}

TEST(RemapTable, AutomaticTileSizeIsChosenPerView) {
  // The default (tile 0): 64-pixel tiles for a perspective view well inside the mirror (all interp at 64), 32
  // for a panorama that crosses the rim and the camera's reflection (it has per-pixel tiles at either size, four
  // times the pixels of them at 64). An explicit size applies to every view.
  const Layout layout = ArticleAndRimPanorama(1, 900, 200);
  const AnyModel exact = AnyModel::Exact(Rig());
  const RemapTable a = BuildRemapTable(exact, layout, {});
  ASSERT_EQ(a.views.size(), 2u);
  EXPECT_EQ(a.views[0].tile, 64);
  EXPECT_EQ(a.views[0].tiles_x, (a.views[0].view.width + 63) / 64);
  EXPECT_EQ(a.views[0].dense_tiles, 0);
  EXPECT_EQ(a.views[1].tile, 32);
  RemapOptions fixed;
  fixed.tile = 64;
  const RemapTable b = BuildRemapTable(exact, layout, fixed);
  EXPECT_EQ(b.views[1].tile, 64);
  EXPECT_GT(int64_t(b.views[1].dense_tiles) * 64 * 64, int64_t(a.views[1].dense_tiles) * 32 * 32);
  fixed.tile = 32;
  const RemapTable c = BuildRemapTable(exact, layout, fixed);
  EXPECT_EQ(c.views[0].tile, 32);
  EXPECT_EQ(c.views[1].tile, 32);
  // Views at 64 and 32 decode to the same coordinates within both tables' interpolation tolerance.
  std::vector<float> x64, y64, x32, y32;
  a.DecodeView(0, &x64, &y64);
  c.DecodeView(0, &x32, &y32);
  double worst = 0;
  for (size_t k = 0; k < x64.size(); ++k)
    worst = std::max(worst, std::hypot(double(x64[k]) - x32[k], double(y64[k]) - y32[k]));
  EXPECT_LT(worst, 2.0 / 64 + 2e-3);
}

// FNV-1a 64 as the mapping file's checksum (to write files that are intact but old or inconsistent).
std::string WithChecksum(std::string body) {
  uint64_t h = 1469598103934665603ull;
  for (const char ch : body) h = (h ^ static_cast<unsigned char>(ch)) * 1099511628211ull;
  body.append(reinterpret_cast<const char*>(&h), 8);
  return body;
}

TEST(MappingFile, RoundTripAndDetectsCorruptionAndVersion) {
  // Two article views (64-pixel tiles) and a panorama that crosses the rim (32): tile sizes differ per view.
  const Layout layout = ArticleAndRimPanorama(2, 600, 150);
  const RemapTable t = BuildRemapTable(AnyModel::Exact(Rig()), layout, {}, R"({"hovs": "test"})");
  ASSERT_EQ(t.views[0].tile, 64);
  ASSERT_EQ(t.views[2].tile, 32);
  const auto dir = TempDir();
  const auto path = dir / "article.hmap";
  SaveRemapTable(path, t);
  const RemapTable back = LoadRemapTable(path);
  ASSERT_EQ(back.views.size(), 3u);
  EXPECT_EQ(back.header, t.header);
  for (int v = 0; v < 3; ++v) {
    EXPECT_EQ(back.views[v].tile, t.views[v].tile);
    std::vector<float> a, b, c, d;
    t.DecodeView(v, &a, &b);
    back.DecodeView(v, &c, &d);
    EXPECT_EQ(a, c);
    EXPECT_EQ(b, d);
  }
  EXPECT_NE(MappingFileHeader(path).find("\"exact\""), std::string::npos);

  const auto read = [](const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string bytes = read(path);
  const auto write = [&](const std::string& name, const std::string& content) {
    std::ofstream out(dir / name, std::ios::binary);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    return dir / name;
  };
  const auto expect_error = [&](const std::filesystem::path& p, const std::string& what) {
    try {
      LoadRemapTable(p);
      ADD_FAILURE() << "no error for " << p;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(p.filename().string()), std::string::npos) << e.what();
    }
  };
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x10;
  expect_error(write("flipped.hmap", flipped), "checksum");
  expect_error(write("truncated.hmap", bytes.substr(0, bytes.size() - 100)), "checksum");
  std::string version = bytes;
  version[8] = 99;
  expect_error(write("version.hmap", version), "version");
  // Version 1 (one tile size for all views, written in the header) is still read.
  {
    RemapOptions o32;
    o32.tile = 32;
    const auto p32 = dir / "tile32.hmap";
    SaveRemapTable(p32, BuildRemapTable(AnyModel::Exact(Rig()), layout, o32));
    std::string v1 = read(p32);
    v1 = v1.substr(0, v1.size() - 8);
    v1[8] = 1;
    const RemapTable old = LoadRemapTable(write("version1.hmap", WithChecksum(v1)));
    ASSERT_EQ(old.views.size(), 3u);
    EXPECT_EQ(old.views[0].tile, 32);
  }
  // A view's tile size that is not one of the four (intact checksum): the first view's record follows the header.
  const std::string body = bytes.substr(0, bytes.size() - 8);
  uint32_t header_length = 0;
  std::memcpy(&header_length, body.data() + 12, 4);
  std::string bad_tile = body;
  const uint32_t seventeen = 17;
  std::memcpy(&bad_tile[16 + header_length + 4 + 8], &seventeen, 4);
  expect_error(write("tile.hmap", WithChecksum(bad_tile)), "tile size 17");
  expect_error(write("garbage.hmap", "hello world, not a mapping file"), "not a hovs mapping file");
  std::filesystem::remove_all(dir);
}

// A mapping file edited and given a valid checksum again (FNV-1a guards against damage, not edits) must not make
// the remap read outside its frame: every edit is refused on load or, where the file stays consistent, remapped
// through the clamped kernels. Run under AddressSanitizer by the test script, where any stray read would stop it.
TEST(MappingFile, EditedTilesWithAValidChecksumCannotReadOutsideTheFrame) {
  const Layout layout = ArticleAndRimPanorama(1, 400, 100);
  const RemapTable t = BuildRemapTable(AnyModel::Exact(Rig()), layout, {});
  const auto dir = TempDir();
  const auto path = dir / "m.hmap";
  SaveRemapTable(path, t);
  std::string body;
  {
    std::ifstream in(path, std::ios::binary);
    body.assign(std::istreambuf_iterator<char>(in), {});
    body.resize(body.size() - 8);
  }
  uint32_t header_length = 0;
  std::memcpy(&header_length, body.data() + 12, 4);
  const size_t tiles0 = 16 + header_length + 4 + 16;  // view 0's tiles follow its four counts
  // View 0's first interp tile marked inside (the article view lies well inside the image).
  size_t at = 0;
  for (size_t k = 0; k < t.views[0].tiles.size(); ++k)
    if (t.views[0].tiles[k].kind == TileKind::kInterp && t.views[0].tiles[k].inside) {
      at = tiles0 + k * sizeof(Tile);
      break;
    }
  ASSERT_GT(at, 0u);
  const auto load = [&](const std::string& edited) {
    const std::string file = WithChecksum(edited);
    std::ofstream(dir / "e.hmap", std::ios::binary).write(file.data(), std::streamsize(file.size()));
    return LoadRemapTable(dir / "e.hmap");
  };
  const auto refused = [&](const std::function<void(Tile*)>& edit, const std::string& needle) {
    std::string e = body;
    Tile tile;
    std::memcpy(&tile, &e[at], sizeof tile);
    edit(&tile);
    std::memcpy(&e[at], &tile, sizeof tile);
    try {
      load(e);
      ADD_FAILURE() << "accepted an edit expected to be refused (" << needle << ")";
    } catch (const Error& err) {
      EXPECT_NE(std::string(err.what()).find(needle), std::string::npos) << err.what();
      EXPECT_NE(std::string(err.what()).find("tile ("), std::string::npos) << err.what();
    }
  };
  refused([](Tile* x) { x->x[4] += 5000; }, "samples outside its source image");
  refused([](Tile* x) { x->y[0] = -40; }, "samples outside its source image");
  refused([](Tile* x) { x->x[8] = NAN; }, "not finite");
  refused([](Tile* x) { x->inside = 0, x->x[0] = 3e9f; }, "fixed-point range");
  refused([](Tile* x) { x->kind = static_cast<TileKind>(7); }, "bad tile kind");
  refused([](Tile* x) { x->level = 9; }, "bad pyramid level");
  refused([](Tile* x) { x->kind = TileKind::kDense, x->dense_index = 1u << 30; }, "dense tile index");

  // Random edits of the tile and dense records (checksum made valid again): refused, or remapped without a read
  // outside the frame (the clamped kernels take whatever a consistent file holds).
  const size_t tiles_end = body.size();
  std::mt19937 rng(7);
  std::uniform_int_distribution<size_t> pos(tiles0, tiles_end - 1);
  std::uniform_int_distribution<int> byte(0, 255);
  Image8 frame;
  frame.width = t.source_width, frame.height = t.source_height, frame.channels = 3;
  frame.data.assign(size_t(frame.width) * frame.height * 3, 90);
  int loaded = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string e = body;
    for (int k = 0; k < 1 + trial % 4; ++k) e[pos(rng)] = static_cast<char>(byte(rng));
    try {
      const RemapTable edited = load(e);
      Remapper r(edited);
      std::vector<Image8> views;
      r.Run(frame.View(PixelFormat::kRgb8), Interpolation::kBilinear, &views);
      r.Run(frame.View(PixelFormat::kBayerRggb8), Interpolation::kBilinear, &views);
      ++loaded;
    } catch (const Error&) {}
  }
  EXPECT_GT(loaded, 0) << "some edits (pixel values of dense tiles) leave a consistent file";
  std::filesystem::remove_all(dir);
}

// Random interior coordinates of a row, in 16.16.
kernels::RowCoords RandomRow(std::mt19937* rng, int n, int w, int h, std::vector<int32_t>* xs,
                             std::vector<int32_t>* ys) {
  std::uniform_real_distribution<double> X(3, w - 5), Y(3, h - 5);
  xs->resize(n), ys->resize(n);
  for (int i = 0; i < n; ++i) (*xs)[i] = int32_t(X(*rng) * 65536), (*ys)[i] = int32_t(Y(*rng) * 65536);
  kernels::RowCoords c;
  c.xs = xs->data(), c.ys = ys->data();
  return c;
}

// Every instruction set this CPU runs, against the scalar kernels: rows (random coordinates and the row
// polynomial, lengths that leave tails) and whole interp tiles, RGB, grey and Bayer.
TEST(Kernels, VectorAndScalarAgreeBitForBit) {
  std::mt19937 rng(11);
  const int w = 300, h = 200;
  std::vector<uint8_t> rgb(w * h * 3), grey(w * h);
  for (auto& v : rgb) v = uint8_t(rng());
  for (auto& v : grey) v = uint8_t(rng());
  std::vector<kernels::Isa> isas;
  for (int i = 0; i <= static_cast<int>(kernels::DetectedIsa()); ++i) isas.push_back(static_cast<kernels::Isa>(i));
  int compared = 0;
  for (const kernels::Isa isa : isas) {
    kernels::LimitIsa(isa);
    ASSERT_EQ(kernels::ActiveIsa(), isa);
    for (int trial = 0; trial < 24; ++trial) {
      std::vector<int32_t> xs, ys;
      const int n = 33 + trial;
      kernels::RowCoords c = RandomRow(&rng, n, w, h, &xs, &ys);
      if (trial % 2) {  // the polynomial form of interp tiles
        c.xs = c.ys = nullptr;
        c.poly = {float((20 + trial) * 65536), 0.9f * 65536, 0.01f * 65536,
                  float((30 + trial) * 65536), 0.3f * 65536, -0.002f * 65536};
      }
      const std::string what = std::string(kernels::ToString(isa)) + " trial " + std::to_string(trial);
      std::vector<uint8_t> a(3 * n), b(3 * n);
      kernels::BilinearRgbRow(rgb.data(), 3 * w, c, 0, n, a.data());
      kernels::BilinearRgbRowScalar(rgb.data(), 3 * w, c, 0, n, b.data());
      EXPECT_EQ(a, b) << "rgb " << what;
      kernels::BayerRgbRow(grey.data(), w, c, 0, n, a.data());
      kernels::BayerRgbRowScalar(grey.data(), w, c, 0, n, b.data());
      EXPECT_EQ(a, b) << "bayer " << what;
      std::vector<uint8_t> g1(n), g2(n);
      kernels::BilinearGrayRow(grey.data(), w, c, 0, n, g1.data());
      kernels::BilinearGrayRowScalar(grey.data(), w, c, 0, n, g2.data());
      EXPECT_EQ(g1, g2) << "grey " << what;
      ++compared;
    }
    // Whole tiles (partial ones too): a rotated, scaled, slightly curved patch well inside the image, written
    // into a larger output with a row stride, against the scalar rows of the same polynomials. Trials 6 and 7
    // take the AVX-512 Bayer tile's other path (row by row from the mosaic): a footprint wider than its patch
    // (4 source columns per output pixel), and one whose taps reach a row's last 3 bytes. Trials 8-11 are
    // 64-pixel tiles (what RemapOptions::tile = 0 gives views that fit): whole and partial, with a footprint
    // the patch holds and, in trial 11, one wider than the RGB patch (row by row).
    for (int trial = 0; trial < 12; ++trial) {
      const bool large = trial >= 8;
      const int T = large ? 64 : 32;
      const int nu = large ? (trial % 2 ? 64 : 37) : trial % 3 == 0 || trial == 7 ? 32 : 9 + 5 * trial;
      const int nv = large ? (trial == 9 ? 29 : 64) : trial % 2 ? 32 : 7 + trial;
      const float xscale = trial == 6 ? 4.f : trial == 11 ? 1.5f : large ? 0.6f : 1.f;
      const float x0 = trial == 7 ? w - 42.f : large ? 40.f + trial : 60.f + trial;
      Tile t;
      t.kind = TileKind::kInterp;
      for (int r = 0; r < 3; ++r)
        for (int q = 0; q < 3; ++q) {
          const float u = 0.5f * T * q, v = 0.5f * T * r;
          t.x[3 * r + q] = x0 + xscale * (1.3f * u - 0.4f * v + 0.01f * u * v * 32 / T);
          t.y[3 * r + q] =
              (large ? 30 : 50) + 0.5f * u + (large ? 0.9f : 1.1f) * v - 0.006f * u * u * 32 / T + 0.7f * trial;
        }
      const ptrdiff_t os = 3 * 72;
      std::vector<uint8_t> got(size_t(os) * T, 7), want(size_t(os) * T, 7), ggot(72 * T, 7), gwant(72 * T, 7);
      std::vector<uint8_t> bgot(size_t(os) * T, 7), bwant(size_t(os) * T, 7);
      kernels::BilinearRgbTile(rgb.data(), 3 * w, t, T, nu, nv, got.data(), os);
      kernels::BilinearGrayTile(grey.data(), w, t, T, nu, nv, ggot.data(), 72);
      kernels::BayerRgbTile(grey.data(), w, t, T, nu, nv, bgot.data(), os);
      kernels::RowCoords c;
      for (int j = 0; j < nv; ++j) {
        c.poly = InterpRowPoly(t, T, j);
        kernels::BilinearRgbRowScalar(rgb.data(), 3 * w, c, 0, nu, want.data() + j * os);
        kernels::BilinearGrayRowScalar(grey.data(), w, c, 0, nu, gwant.data() + j * 72);
        kernels::BayerRgbRowScalar(grey.data(), w, c, 0, nu, bwant.data() + j * os);
      }
      const std::string what = std::string(kernels::ToString(isa)) + " tile " + std::to_string(trial);
      EXPECT_EQ(got, want) << "rgb " << what;  // also: nothing written outside the tile's nu x nv pixels
      EXPECT_EQ(ggot, gwant) << "grey " << what;
      EXPECT_EQ(bgot, bwant) << "bayer " << what;
    }
  }
  kernels::LimitIsa(kernels::Isa::kAvx512);
  EXPECT_EQ(compared, 24 * static_cast<int>(isas.size()));
}

TEST(Kernels, BilinearReproducesALinearRamp) {
  // value = 0.25 x + 0.3 y + 5 per channel (with an offset per channel): bilinear is exact on a plane, so the
  // output equals the plane at the sampled position within rounding (1/64 px positions, integer output).
  const int w = 400, h = 300;
  std::vector<uint8_t> rgb(w * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) rgb[3 * (y * w + x) + c] = uint8_t(std::lround(0.25 * x + 0.3 * y + 5 + 5 * c));
  std::mt19937 rng(5);
  std::vector<int32_t> xs, ys;
  const kernels::RowCoords c = RandomRow(&rng, 500, w, h, &xs, &ys);
  std::vector<uint8_t> out(3 * 500);
  kernels::BilinearRgbRow(rgb.data(), 3 * w, c, 0, 500, out.data());
  for (int i = 0; i < 500; ++i)
    for (int ch = 0; ch < 3; ++ch) {
      const double expect = 0.25 * xs[i] / 65536.0 + 0.3 * ys[i] / 65536.0 + 5 + 5 * ch;
      EXPECT_NEAR(out[3 * i + ch], expect, 1.0) << i;
    }
}

TEST(Remap, BayerInputGivesTheRgbResultOnSmoothContent) {
  // A smooth colour image and its RGGB mosaic: the demosaicing remap is close to the RGB remap.
  const auto rig = Rig();
  Layout layout = PresetLayout("article");
  layout.views.resize(1);
  const RemapTable t = BuildRemapTable(AnyModel::Exact(rig), layout, {});
  const int W = 2750, H = 2200;
  std::vector<uint8_t> rgb(size_t(W) * H * 3), mosaic(size_t(W) * H);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const double r = 128 + 100 * std::sin(x * 0.01), g = 128 + 100 * std::cos(y * 0.012),
                   b = 128 + 80 * std::sin((x + y) * 0.008);
      uint8_t* p = &rgb[3 * (size_t(y) * W + x)];
      p[0] = uint8_t(std::lround(r)), p[1] = uint8_t(std::lround(g)), p[2] = uint8_t(std::lround(b));
      mosaic[size_t(y) * W + x] = p[(y % 2) + (x % 2)];  // RGGB: (0,0) R, (1,0)/(0,1) G, (1,1) B
    }
  Remapper remapper(t);
  std::vector<Image8> a, b;
  remapper.Run({rgb.data(), W, H, size_t(W) * 3, PixelFormat::kRgb8}, Interpolation::kBilinear, &a);
  remapper.Run({mosaic.data(), W, H, size_t(W), PixelFormat::kBayerRggb8}, Interpolation::kBilinear, &b);
  ASSERT_EQ(a[0].data.size(), b[0].data.size());
  double sum = 0;
  int worst = 0;
  for (size_t k = 0; k < a[0].data.size(); ++k) {
    const int d = std::abs(int(a[0].data[k]) - int(b[0].data[k]));
    sum += d;
    worst = std::max(worst, d);
  }
  EXPECT_LT(sum / a[0].data.size(), 1.0);
  EXPECT_LE(worst, 4);
}

TEST(Remap, EveryInstructionSetGivesTheSameViews) {
  // Whole remaps (interp, dense and empty tiles, partial tiles at the views' edges, the per-thread bands and
  // their streamed copy): one perspective view and a small panorama that includes the rim and the camera's own
  // reflection, RGB, grey and Bayer input, with the kernels limited to each instruction set the CPU runs. The
  // perspective view gets 64-pixel tiles, the panorama 32.
  const auto rig = Rig();
  Layout layout = ArticleAndRimPanorama(1, 517, 150);
  layout.views[0].width = 900, layout.views[0].height = 455;  // partial tiles at the right and bottom edges
  const RemapTable t = BuildRemapTable(AnyModel::Exact(rig), layout, {});
  ASSERT_EQ(t.views[0].tile, 64);
  ASSERT_EQ(t.views[1].tile, 32);
  int dense = 0, empty = 0;
  for (const auto& v : t.views) dense += v.dense_tiles, empty += v.empty_tiles;
  ASSERT_GT(dense, 0);
  ASSERT_GT(empty, 0);
  const int W = 2750, H = 2200;
  std::mt19937 rng(3);
  std::vector<uint8_t> rgb(size_t(W) * H * 3), grey(size_t(W) * H);
  for (auto& v : rgb) v = uint8_t(rng());
  for (auto& v : grey) v = uint8_t(rng());
  const std::vector<std::pair<ImageView, const char*>> inputs = {
      {{rgb.data(), W, H, size_t(W) * 3, PixelFormat::kRgb8}, "rgb"},
      {{grey.data(), W, H, size_t(W), PixelFormat::kGray8}, "grey"},
      {{grey.data(), W, H, size_t(W), PixelFormat::kBayerRggb8}, "bayer"}};
  Remapper remapper(t);
  for (const auto& [input, name] : inputs) {
    kernels::LimitIsa(kernels::Isa::kScalar);
    std::vector<Image8> want;
    remapper.Run(input, Interpolation::kBilinear, &want);
    for (int i = 1; i <= static_cast<int>(kernels::DetectedIsa()); ++i) {
      kernels::LimitIsa(static_cast<kernels::Isa>(i));
      std::vector<Image8> got;
      remapper.Run(input, Interpolation::kBilinear, &got);
      ASSERT_EQ(got.size(), want.size());
      for (size_t v = 0; v < got.size(); ++v)
        EXPECT_TRUE(got[v].data == want[v].data)
            << name << ", view " << v << ", " << kernels::ToString(kernels::ActiveIsa());
    }
  }
  kernels::LimitIsa(kernels::Isa::kAvx512);
}

TEST(Remap, InterpolationsAgreeOnSmoothContentAndNearestIsExactOnIntegers) {
  const auto rig = Rig();
  Layout layout;
  layout.name = "one";
  ViewSpec v;
  v.name = "v", v.width = 200, v.height = 150, v.hfov_deg = 20;
  layout.views.push_back(v);
  const RemapTable t = BuildRemapTable(AnyModel::Exact(rig), layout, {});
  const int W = 2750, H = 2200;
  std::vector<uint8_t> grey(size_t(W) * H);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) grey[size_t(y) * W + x] = uint8_t(128 + 100 * std::sin(x * 0.02) * std::cos(y * 0.015));
  Remapper r(t);
  const ImageView src{grey.data(), W, H, size_t(W), PixelFormat::kGray8};
  std::vector<Image8> bl, bc, nn;
  r.Run(src, Interpolation::kBilinear, &bl);
  r.Run(src, Interpolation::kBicubic, &bc);
  r.Run(src, Interpolation::kNearest, &nn);
  ASSERT_EQ(bl[0].channels, 1);
  std::vector<float> mx, my;
  t.DecodeView(0, &mx, &my);
  int worst_bc = 0;
  for (size_t k = 0; k < bl[0].data.size(); ++k) {
    worst_bc = std::max(worst_bc, std::abs(int(bl[0].data[k]) - int(bc[0].data[k])));
    const int ix = int(std::lround(mx[k])), iy = int(std::lround(my[k]));
    EXPECT_EQ(nn[0].data[k], grey[size_t(iy) * W + ix]) << k;
    if (::testing::Test::HasFailure()) break;
  }
  EXPECT_LE(worst_bc, 3);
}

// The pyramid's levels against the 2 x 2 box mean written out pixel by pixel: odd and even sizes (the last
// column / row counted twice), rows with padding, grey, RGB and a Bayer mosaic (its cells as RGB pixels).
TEST(Remap, PyramidLevelIsTheRoundedBoxMean) {
  std::mt19937 rng(5);
  struct Case {
    int w, h;
    PixelFormat f;
  };
  for (const Case c :
       {Case{9, 7, PixelFormat::kGray8}, Case{10, 6, PixelFormat::kGray8}, Case{67, 5, PixelFormat::kRgb8},
        Case{66, 9, PixelFormat::kRgb8}, Case{70, 8, PixelFormat::kBayerRggb8}}) {
    const int C = c.f == PixelFormat::kRgb8 ? 3 : 1;
    const size_t stride = size_t(c.w) * C + 5;
    std::vector<uint8_t> in(stride * c.h);
    for (auto& v : in) v = uint8_t(rng());
    const auto at = [&](int x, int y, int ch) {
      return int(in[size_t(std::min(y, c.h - 1)) * stride + size_t(std::min(x, c.w - 1)) * C + ch]);
    };
    Image8 out;
    DownsampleHalf({in.data(), c.w, c.h, stride, c.f}, &out);
    const std::string what = std::to_string(c.w) + " x " + std::to_string(c.h) + " " + ToString(c.f);
    ASSERT_EQ(out.width, (c.w + 1) / 2) << what;
    ASSERT_EQ(out.height, (c.h + 1) / 2) << what;
    const int OC = c.f == PixelFormat::kBayerRggb8 ? 3 : C;
    ASSERT_EQ(out.channels, OC) << what;
    int wrong = 0;
    for (int j = 0; j < out.height; ++j)
      for (int i = 0; i < out.width; ++i)
        for (int ch = 0; ch < OC; ++ch) {
          int want = 0;
          if (c.f == PixelFormat::kBayerRggb8) {
            want = ch == 0   ? at(2 * i, 2 * j, 0)
                   : ch == 2 ? at(2 * i + 1, 2 * j + 1, 0)
                             : (at(2 * i + 1, 2 * j, 0) + at(2 * i, 2 * j + 1, 0) + 1) >> 1;
          } else {
            want = (at(2 * i, 2 * j, ch) + at(2 * i + 1, 2 * j, ch) + at(2 * i, 2 * j + 1, ch) +
                    at(2 * i + 1, 2 * j + 1, ch) + 2) >>
                   2;
          }
          wrong += out.data[(size_t(j) * out.width + i) * OC + ch] != want;
        }
    EXPECT_EQ(wrong, 0) << what;
  }
  Image8 out;
  std::vector<uint8_t> odd(9 * 8);
  EXPECT_THROW(DownsampleHalf({odd.data(), 9, 8, 9, PixelFormat::kBayerRggb8}, &out), Error);
  EXPECT_THROW(DownsampleHalf({odd.data(), 9, 8, 4, PixelFormat::kGray8}, &out), Error);
}

TEST(Remap, RejectsBadInput) {
  Layout layout = PresetLayout("article");
  layout.views.resize(1);
  const RemapTable t = BuildRemapTable(AnyModel::Exact(Rig()), layout, {});
  Remapper r(t);
  std::vector<uint8_t> img(100 * 100 * 3);
  std::vector<Image8> out;
  try {
    r.Run({img.data(), 100, 100, 300, PixelFormat::kRgb8}, Interpolation::kBilinear, &out);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find("2750 x 2200"), std::string::npos) << e.what(); }
  ViewSpec wide;
  wide.name = "wide", wide.hfov_deg = 180;
  EXPECT_THROW(wide.Check("test"), Error);
  wide.hfov_deg = 120, wide.width = 0;
  EXPECT_THROW(wide.Check("test"), Error);
  EXPECT_THROW(PresetLayout("nonsense"), Error);
  Layout dup = PresetLayout("article");
  dup.views[1].name = dup.views[0].name;
  EXPECT_THROW(dup.Check("test"), Error);
  RemapOptions o;
  o.tile = 12;
  EXPECT_THROW(o.Check("test"), Error);
}

// Views that need more memory than is left are refused before any mapping is built, with their size and both
// amounts; the bound counts every view's output and mapping and the largest view's float copy.
TEST(Layout, ViewsLargerThanTheMemoryLeftAreRefused) {
  ViewSpec a, b;
  a.name = "a", a.width = 1000, a.height = 500;
  b.name = "b", b.width = 2000, b.height = 1000;
  const std::vector<ViewSpec> views = {a, b};
  const std::size_t need = ViewsMemoryBytes(views);
  EXPECT_EQ(need, std::size_t(2500000) * 11 + std::size_t(2000000) * 12);
  EXPECT_NO_THROW(CheckViewsMemory("--layout x", views, need));
  EXPECT_NO_THROW(CheckViewsMemory("--layout x", views, std::nullopt));
  try {
    CheckViewsMemory("--layout x.yaml", views, need - 1);
    ADD_FAILURE() << "views one byte too large were accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    for (const char* needle : {"--layout x.yaml", "2 views", "2.5 megapixels", "0.05 GB", "are available"})
      EXPECT_NE(what.find(needle), std::string::npos) << needle << " in: " << what;
  }
}

TEST(Layout, YamlFileIsValidated) {
  const auto dir = TempDir();
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return dir / name;
  };
  const Layout l = LoadLayout(write("ok.yaml",
                                    "views:\n  - {name: a, yaw: 10, pitch: -20, hfov: 50, width: 64, height: 48}\n"
                                    "  - {name: p, type: cylindrical, width: 720, height: 100}\n"));
  ASSERT_EQ(l.views.size(), 2u);
  EXPECT_DOUBLE_EQ(l.views[0].yaw_deg, 10);
  EXPECT_EQ(l.views[1].type, ViewProjection::kCylindrical);
  const auto expect_error = [&](const std::string& text, const std::string& what) {
    try {
      LoadLayout(write("bad.yaml", text));
      ADD_FAILURE() << "no error for " << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.yaml"), std::string::npos) << e.what();
    }
  };
  expect_error("views:\n  - {name: a, hfov: 190}\n", "hfov");
  expect_error("views:\n  - {name: a, yaw: 10, colour: red}\n", "unknown key");
  expect_error("views:\n  - {name: a, type: fisheye}\n", "unknown view type");
  expect_error("views:\n  - {name: a, type: cylindrical, yaw: 3}\n", "perspective views only");
  expect_error("views: []\n", "list of views");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hovs::unwrap

namespace hovs::unwrap {
namespace {

// Presets follow the model's field: for the reference rig the panorama spans the mirror from the camera's
// reflection to the rim (whose elevation the design gives); a calibrated polynomial model's panorama spans its
// annulus; the article's views stay at pitch -30 where they fit and are pitched up only as far as needed where
// the field reaches higher (a camera that sees above the horizon).
TEST(Layout, PresetsFollowTheModelsField) {
  const auto rig = test::AlignedRig();
  const AnyModel exact = AnyModel::Exact(rig);
  const ModelField f = FieldOfModel(exact);
  const double rim_el = std::atan2(rig.mirror.RimZ(), rig.mirror.RimRadius()) * 180 / M_PI;
  EXPECT_NEAR(f.elevation_max_deg, rim_el, 0.3);
  EXPECT_GT(f.elevation_min_deg, -88) << "the camera's reflection is left out";
  EXPECT_LT(f.elevation_min_deg, -60);
  const Layout pano = PresetLayout("panorama", exact);
  EXPECT_EQ(pano.views[0].elevation_min_deg, f.elevation_min_deg);
  EXPECT_EQ(pano.views[0].elevation_max_deg, f.elevation_max_deg);
  for (const auto& v : PresetLayout("article", exact).views) EXPECT_EQ(v.pitch_deg, -30);
  // A polynomial model of the same rig with an annulus reaching 20 degrees above the horizon.
  PolynomialModel<double> poly = PolynomialFromCatadioptric(rig, 5);
  const auto rho_at = [&](double el_deg) {  // the radius whose elevation is el_deg (bisection)
    double lo = poly.rho_min, hi = 3 * poly.rho_max;
    for (int k = 0; k < 100; ++k) {
      const double mid = 0.5 * (lo + hi);
      (std::atan2(poly.F(mid), mid) * 180 / M_PI < el_deg ? lo : hi) = mid;
    }
    return lo;
  };
  poly.rho_min = rho_at(-50), poly.rho_max = rho_at(20);
  poly.FitInverse();
  const ModelField fp = FieldOfModel(AnyModel::Polynomial(poly));
  EXPECT_NEAR(fp.elevation_min_deg, -50, 0.3);
  EXPECT_NEAR(fp.elevation_max_deg, 20, 0.3);
  const Layout article = PresetLayout("article", AnyModel::Polynomial(poly));
  const double half_v = std::atan(std::tan(32.5 * M_PI / 180) * 700 / 1200) * 180 / M_PI;
  for (const auto& v : article.views) EXPECT_NEAR(v.pitch_deg, fp.elevation_min_deg + half_v, 1e-9);
  EXPECT_EQ(PresetLayout("longlat", exact).views[0].elevation_max_deg, 90);
}

}  // namespace
}  // namespace hovs::unwrap
