// A panorama of the whole rig: the article's two units (scenes/reference_stereo.yaml) each expand it from their
// own frame and the two are blended around the perpendicular to the baseline. Compared with the same blend of
// truth panoramas (pinhole renders at each unit's own viewpoint resampled into the panorama): the expansion and
// the blend add no seam (PSNR over the overlap and over the whole panorama). The parallax between the two
// viewpoints is in the truth as well, so this measures hovs' resampling and blending, not the parallax.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "io/image_io.h"
#include "raytrace/render.h"
#include "scenes/scene_config.h"
#include "scenes/truth_views.h"
#include "unwrap/layout.h"
#include "unwrap/rig_mapping.h"

namespace hovs::unwrap {
namespace {

double Psnr(double se, int64_t n) { return 10 * std::log10(255.0 * 255.0 / (se / std::max<int64_t>(n, 1))); }

TEST(RigBlend, APanoramaOfBothUnitsMatchesTheBlendOfTheirTruthPanoramas) {
  const auto cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_stereo.yaml");
  const auto& su = cfg.description.units;
  ASSERT_EQ(su.size(), 2u);
  std::vector<RigUnitModel> units;
  for (const auto& u : su)
    units.push_back({u.name, AnyModel::Exact(u.rig), u.world_from_mirror.Inverse() * su[0].world_from_mirror, true});
  const Layout layout = ParseLayout(
      "views:\n  - {name: rig, unit: all, type: cylindrical, width: 3600, height: 400, elevation_min: -45, "
      "elevation_max: -8}\n",
      "layout.yaml", "rig");
  const RigMapping m = BuildRigMapping(units, layout, {});
  ASSERT_EQ(m.ViewCount(), 1);
  ASSERT_EQ(m.blends.size(), 1u);
  EXPECT_EQ(m.UnitName(0), "all");

  // Each unit's frame, rendered whole.
  const raytrace::RayScene scene(cfg.description);
  raytrace::RenderOptions ro = cfg.render;
  ro.samples = 8;
  ro.ground_truth = false;
  std::vector<std::vector<uint8_t>> frames;
  for (int u = 0; u < 2; ++u) {
    const raytrace::Frame f = raytrace::Render(scene, raytrace::ViewCamera::Unit(u), ro);
    std::vector<uint8_t> b(f.rgb.size());
    for (size_t k = 0; k < b.size(); ++k) b[k] = uint8_t(std::lround(std::clamp(f.rgb[k], 0.f, 1.f) * 255));
    frames.push_back(std::move(b));
  }
  const int W = units[0].model.width(), H = units[0].model.height();
  std::vector<Image8> out;
  RigRemapper(m).Run({{frames[0].data(), W, H, size_t(W) * 3, PixelFormat::kRgb8},
                      {frames[1].data(), W, H, size_t(W) * 3, PixelFormat::kRgb8}},
                     Interpolation::kBilinear, &out);
  ASSERT_EQ(out.size(), 1u);

  // The truth: each unit's part of the panorama (in its own frame) rendered at its viewpoint, blended alike.
  const RigBlend& b = m.blends[0];
  std::vector<std::vector<uint8_t>> truth;
  for (int p = 0; p < 2; ++p) {
    const auto& part = m.tables[b.parts[p].first].views[b.parts[p].second];
    truth.push_back(scenes::RenderTruthPanorama(cfg, m.units[b.parts[p].first], part.view, 16, "reference_stereo"));
  }
  const Image8& o = out[0];
  double se_overlap = 0, se_all = 0;
  int64_t n_overlap = 0, n_all = 0;
  std::vector<uint8_t> blended(o.data.size());
  for (size_t i = 0; i < size_t(o.width) * o.height; ++i) {
    const int w0 = b.weights[0][i], w1 = b.weights[1][i];
    if (w0 + w1 == 0) continue;
    for (int c = 0; c < 3; ++c) {
      const double t = (truth[0][3 * i + c] * w0 + truth[1][3 * i + c] * w1) / 255.0;
      const double e = std::pow(o.data[3 * i + c] - t, 2);
      blended[3 * i + c] = static_cast<uint8_t>(std::lround(t));
      se_all += e, ++n_all;
      if (w0 > 0 && w1 > 0) se_overlap += e, ++n_overlap;
    }
  }
  const double psnr_overlap = Psnr(se_overlap, n_overlap), psnr_all = Psnr(se_all, n_all);
  std::printf("rig panorama: PSNR %.2f dB over the overlap (%lld px), %.2f dB over all (%lld px)\n", psnr_overlap,
              static_cast<long long>(n_overlap / 3), psnr_all, static_cast<long long>(n_all / 3));
  if (const char* dump = std::getenv("HOVS_DUMP_UNWRAP")) {
    const auto write = [&](const std::string& name, const std::vector<uint8_t>& px) {
      std::vector<float> f(px.begin(), px.end());
      for (float& v : f) v /= 255.f;
      io::WriteImage(std::string(dump) + name, o.width, o.height, 3, f, 8);
    };
    write("_rig_panorama.png", o.data);
    write("_rig_truth.png", blended);
  }
  // Both units contribute, and the overlap is the two ramps (2 x 20 degrees of 360) of the valid rows.
  EXPECT_GT(n_overlap / 3, int64_t(o.width) * o.height / 12);
  EXPECT_GE(psnr_overlap, 30.0);
  EXPECT_GE(psnr_all, 30.0);
  // Unit 0 owns the azimuths away from unit 1 (-x in the rig): the panorama's centre column (azimuth 0, +x) is
  // unit 1's, its first column (azimuth 180) unit 0's.
  const size_t mid_row = size_t(o.height / 2) * o.width;
  EXPECT_EQ(b.weights[1][mid_row + o.width / 2], 255);
  EXPECT_EQ(b.weights[0][mid_row], 255);
}

}  // namespace
}  // namespace hovs::unwrap
