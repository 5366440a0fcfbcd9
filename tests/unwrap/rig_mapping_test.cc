// Rig mappings: views of several units in one pass give exactly what each unit's own remap gives, survive their
// file, and refuse frames that do not belong together.
#include <gtest/gtest.h>

#include <random>

#include "core/error.h"
#include "core/io.h"
#include "tests/core/test_rigs.h"
#include "unwrap/layout.h"
#include "unwrap/rig_mapping.h"

namespace hovs::unwrap {
namespace {
namespace fs = std::filesystem;

constexpr char kLayout[] = R"(views:
  - {name: l_back, unit: left, width: 96, height: 64, yaw: 180, pitch: -30, hfov: 65}
  - {name: r_front, unit: 1, width: 96, height: 64, yaw: 0, pitch: -30, hfov: 65}
  - {name: l_side, unit: left, width: 80, height: 48, yaw: 120, pitch: -20, hfov: 50}
  - {name: r_pano, unit: right, type: cylindrical, width: 180, height: 40, elevation_min: -60, elevation_max: -5}
  - {name: rig_pano, unit: all, type: cylindrical, width: 360, height: 40, elevation_min: -60, elevation_max: -5}
)";

std::vector<RigUnitModel> TwoUnits() {
  auto right = test::AlignedRig();
  right.camera.cx += 7.5;  // a second unit that differs from the first
  // The right unit 0.64 m along +x of the left one (the rig frame is the left unit's mirror frame).
  return {{"left", AnyModel::Exact(test::AlignedRig()), Rigid3d(), true},
          {"right", AnyModel::Exact(right), Rigid3d(Eigen::Quaterniond::Identity(), Vec3d(-0.64, 0, 0)), true}};
}

std::vector<uint8_t> Noise(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<uint8_t> v(n);
  for (auto& b : v) b = static_cast<uint8_t>(rng() & 255);
  return v;
}

TEST(RigMapping, ViewsOfTwoUnitsInOnePassEqualEachUnitsOwnRemap) {
  const auto units = TwoUnits();
  const Layout layout = ParseLayout(kLayout, "layout.yaml", "two");
  ASSERT_TRUE(layout.IsRig());
  const RigMapping m = BuildRigMapping(units, layout, {});
  ASSERT_EQ(m.units, (std::vector<std::string>{"left", "right"}));
  ASSERT_EQ(m.ViewCount(), 5);
  ASSERT_EQ(m.blends.size(), 1u);
  EXPECT_EQ(m.UnitName(4), "all");
  EXPECT_EQ(m.View(2).spec.name, "l_side");
  EXPECT_EQ(m.UnitOf(1), 1);
  const int W = units[0].model.width(), H = units[0].model.height();
  for (const auto format : {PixelFormat::kBayerRggb8, PixelFormat::kGray8}) {
    const auto a = Noise(size_t(W) * H, 1), b = Noise(size_t(W) * H, 2);
    const std::vector<ImageView> frames = {{a.data(), W, H, size_t(W), format}, {b.data(), W, H, size_t(W), format}};
    std::vector<Image8> out;
    RigRemapper(m).Run(frames, Interpolation::kBilinear, &out);
    ASSERT_EQ(out.size(), 5u);
    // The rig's panorama: where one unit has all the weight it is that unit's expansion of its part.
    const RigBlend& blend = m.blends[0];
    int own[2] = {0, 0};
    for (int p = 0; p < 2; ++p) {
      Layout one;
      one.name = "one";
      one.views = {m.tables[blend.parts[p].first].views[blend.parts[p].second].spec};
      std::vector<Image8> ref;
      Remapper(BuildRemapTable(units[p].model, one, {})).Run(frames[p], Interpolation::kBilinear, &ref);
      const int C = out[4].channels;
      for (size_t i = 0; i < blend.weights[p].size(); ++i) {
        if (blend.weights[p][i] != 255) continue;
        ++own[p];
        for (int c = 0; c < C; ++c) ASSERT_EQ(out[4].data[i * C + c], ref[0].data[i * C + c]) << "part " << p;
      }
      for (size_t i = 0; i < blend.weights[p].size(); ++i) {
        const int sum = blend.weights[0][i] + blend.weights[1][i];
        ASSERT_TRUE(sum == 255 || sum == 0) << i;
      }
    }
    EXPECT_GT(own[0], 360 * 40 / 4);
    EXPECT_GT(own[1], 360 * 40 / 4);
    for (int k = 0; k < 4; ++k) {
      const int u = m.UnitOf(k);
      Layout one;
      one.name = "one";
      one.views = {layout.views[k]};
      const RemapTable t = BuildRemapTable(units[u].model, one, {});
      std::vector<Image8> ref;
      Remapper(t).Run(frames[u], Interpolation::kBilinear, &ref);
      EXPECT_EQ(out[k].width, ref[0].width);
      EXPECT_EQ(out[k].channels, format == PixelFormat::kGray8 ? 1 : 3);
      EXPECT_EQ(out[k].data, ref[0].data) << layout.views[k].name;
    }
  }
}

TEST(RigMapping, FileRoundTripsAndDamageIsNamed) {
  const fs::path dir = fs::temp_directory_path() / ("hovs-rigmap-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const RigMapping m = BuildRigMapping(TwoUnits(), ParseLayout(kLayout, "layout.yaml", "two"), {});
  SaveRigMapping(dir / "rig.hmap", m);
  EXPECT_TRUE(IsRigMappingFile(dir / "rig.hmap"));
  EXPECT_FALSE(IsRigMappingFile(dir / "nothing.hmap"));
  const RigMapping back = LoadRigMapping(dir / "rig.hmap");
  EXPECT_EQ(back.units, m.units);
  EXPECT_EQ(back.order, m.order);
  const int W = TwoUnits()[0].model.width(), H = TwoUnits()[0].model.height();
  const auto a = Noise(size_t(W) * H, 3);
  const std::vector<ImageView> frames(2, ImageView{a.data(), W, H, size_t(W), PixelFormat::kGray8});
  std::vector<Image8> x, y;
  RigRemapper(m).Run(frames, Interpolation::kBilinear, &x);
  RigRemapper(back).Run(frames, Interpolation::kBilinear, &y);
  ASSERT_EQ(back.blends.size(), 1u);
  EXPECT_EQ(back.blends[0].weights, m.blends[0].weights);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(x[k].data, y[k].data);

  std::string bytes = ReadFile(dir / "rig.hmap");
  WriteFileAtomic(dir / "cut.hmap", bytes.substr(0, bytes.size() / 2));
  EXPECT_THROW(LoadRigMapping(dir / "cut.hmap"), Error);
  for (const size_t at : {bytes.size() / 2, bytes.size() - 20}) {  // inside a table; inside the blend weights
    std::string damaged = bytes;
    damaged[at] ^= 0x5a;
    WriteFileAtomic(dir / "flip.hmap", damaged);
    try {
      LoadRigMapping(dir / "flip.hmap");
      FAIL() << "a damaged file loaded";
    } catch (const Error& e) { EXPECT_NE(e.message().find("checksum"), std::string::npos) << e.what(); }
  }
  fs::remove_all(dir);
}

TEST(RigMapping, RefusesFramesThatDoNotBelongTogether) {
  const RigMapping m = BuildRigMapping(TwoUnits(), ParseLayout(kLayout, "layout.yaml", "two"), {});
  const int W = TwoUnits()[0].model.width(), H = TwoUnits()[0].model.height();
  const auto a = Noise(size_t(W) * H * 3, 4);
  RigRemapper r(m);
  std::vector<Image8> out;
  const ImageView grey{a.data(), W, H, size_t(W), PixelFormat::kGray8};
  const ImageView rgb{a.data(), W, H, size_t(W) * 3, PixelFormat::kRgb8};
  const ImageView small{a.data(), W / 2, H / 2, size_t(W), PixelFormat::kGray8};
  EXPECT_THROW(r.Run({grey}, Interpolation::kBilinear, &out), Error);  // the second unit's frame is missing
  try {
    r.Run({grey, small}, Interpolation::kBilinear, &out);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.where(), "unit right");
    EXPECT_NE(e.message().find("is for"), std::string::npos) << e.what();
  }
  try {
    r.Run({grey, rgb}, Interpolation::kBilinear, &out);
    FAIL();
  } catch (const Error& e) { EXPECT_NE(e.message().find("one pixel format"), std::string::npos) << e.what(); }
}

TEST(RigMapping, UnitsAreResolvedByNameOrIndexAndUnknownOnesListTheRig) {
  const auto units = TwoUnits();
  ViewSpec v;
  v.name = "x";
  EXPECT_EQ(ResolveUnit(v, units), 0);
  v.unit = "right";
  EXPECT_EQ(ResolveUnit(v, units), 1);
  v.unit = "1";
  EXPECT_EQ(ResolveUnit(v, units), 1);
  v.unit = "2";
  try {
    ResolveUnit(v, units);
    FAIL();
  } catch (const Error& e) { EXPECT_NE(e.message().find("left (0), right (1)"), std::string::npos) << e.what(); }
  const Layout b = PresetLayout("binocular");
  ASSERT_EQ(b.views.size(), 6u);
  EXPECT_EQ(b.views[0].unit, "0");
  EXPECT_EQ(b.views[3].unit, "1");
  EXPECT_DOUBLE_EQ(b.views[1].yaw_deg, 180);
  EXPECT_DOUBLE_EQ(b.views[4].yaw_deg, 0);
  EXPECT_FALSE(PresetLayout("article").IsRig());
  // A view of the whole rig: a panorama, two units, their poses known.
  const auto refuse = [&](const std::string& yaml, std::vector<RigUnitModel> rig, const std::string& needle) {
    try {
      BuildRigMapping(rig, ParseLayout(yaml, "l.yaml", "l"), {});
      FAIL() << yaml;
    } catch (const Error& e) { EXPECT_NE(e.message().find(needle), std::string::npos) << e.what(); }
  };
  refuse("views:\n  - {name: p, unit: all, yaw: 0}\n", units, "a panorama");
  auto unknown = units;
  unknown[1].has_pose = false;
  refuse("views:\n  - {name: p, unit: all, type: cylindrical}\n", unknown, "poses");
  refuse("views:\n  - {name: p, unit: all, type: cylindrical}\n", {units[0]}, "two units");
}

}  // namespace
}  // namespace hovs::unwrap
