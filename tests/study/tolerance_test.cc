// The tolerance study: draws seeded per index, a known sensitivity (the ray error's growth with the lateral
// offset) against a finite difference, shards merged equal to one process byte for byte, bad configs refused.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/io.h"
#include "study/tolerance.h"
#include "tests/cli_helper.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;
using study::ToleranceConfig;

const std::string kReference = std::string(HOVS_SOURCE_DIR) + "/study/reference.yaml";

// The reference config with only the given tolerances.
ToleranceConfig Only(const std::map<std::string, study::Tolerance>& tolerances) {
  ToleranceConfig c = study::LoadToleranceConfig(kReference);
  c.tolerances = tolerances;
  return c;
}

TEST(Tolerance, DrawsAreSeededPerIndexWithTheConfiguredSpread) {
  const ToleranceConfig c = study::LoadToleranceConfig(kReference);
  EXPECT_DOUBLE_EQ(study::DrawErrors(c, 17, 0).offset.x(), study::DrawErrors(c, 17, 0).offset.x());
  EXPECT_NE(study::DrawErrors(c, 17, 0).offset.x(), study::DrawErrors(c, 17, 1).offset.x());
  EXPECT_NE(study::DrawErrors(c, 17, 0).offset.x(), study::DrawErrors(c, 18, 0).offset.x());
  // Normal: lateral offset 0.05 mm per axis; uniform: rim within +-0.05 mm, spread h / sqrt(3).
  double sx = 0, sr = 0, max_rim = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const study::UnitErrors e = study::DrawErrors(c, i, 0);
    sx += e.offset.x() * e.offset.x(), sr += e.rim * e.rim, max_rim = std::max(max_rim, std::abs(e.rim));
  }
  EXPECT_NEAR(std::sqrt(sx / n), 0.05e-3, 0.05e-3 * 0.03);
  EXPECT_NEAR(std::sqrt(sr / n), 0.05e-3 / std::sqrt(3.0), 0.05e-3 * 0.03);
  EXPECT_LE(max_rim, 0.05e-3);
  // Dropping a tolerance leaves the others' draws as they were.
  ToleranceConfig fewer = c;
  fewer.tolerances.erase("mirror_a");
  EXPECT_EQ(study::DrawErrors(fewer, 5, 0).offset.y(), study::DrawErrors(c, 5, 0).offset.y());
  EXPECT_EQ(study::DrawErrors(fewer, 5, 0).a, 0.0);
}

TEST(Tolerance, TheNominalUnitHasNoErrorAndTheFiguresGrowWithTheErrors) {
  const ToleranceConfig c = study::LoadToleranceConfig(kReference);
  const study::ToleranceEvaluator ev(c);
  const study::SampleFigures zero = ev.Evaluate({}, {});
  for (double v : zero.values) EXPECT_LT(v, 1e-9);
  // A tilt about the camera centre keeps the single viewpoint; a lateral offset breaks it.
  const auto tilt = ev.Evaluate(study::SingleError("mirror_tilt", 0.05), {});
  EXPECT_GT(tilt.values[0], 0.05);
  EXPECT_LT(tilt.values[1], 1e-6);
  const auto offset = ev.Evaluate(study::SingleError("lateral_offset", 0.1), {});
  EXPECT_GT(offset.values[1], 1e-3);
  EXPECT_GT(ev.Evaluate(study::SingleError("lateral_offset", 0.2), {}).values[2], offset.values[2]);
}

TEST(Tolerance, TheRayErrorsGrowthWithLateralOffsetMatchesAFiniteDifference) {
  // Monte-Carlo with the lateral offset alone: the slope of the worst ray error over |offset| (least squares
  // through the origin) against the finite difference of the evaluator at a tiny offset along x.
  const ToleranceConfig c = Only({{"lateral_offset", {study::Distribution::kNormal, 0.05}}});
  const auto samples = study::RunSamples(c, 400, 0, 1);
  double sxy = 0, sxx = 0;
  for (const auto& s : samples) {
    const double x = 1e3 * s.left.offset.head<2>().norm();  // mm
    sxy += x * s.figures.values[0], sxx += x * x;
  }
  const double mc_slope = sxy / sxx;
  const study::ToleranceEvaluator ev(c);
  const double h = 1e-4;  // mm
  const double fd_slope =
      (ev.Evaluate(study::SingleError("lateral_offset", h), {}).values[0] - ev.Evaluate({}, {}).values[0]) / h;
  std::printf("[ figure ] ray error per mm of lateral offset: Monte-Carlo %.5f deg/mm, finite difference %.5f deg/mm\n",
              mc_slope, fd_slope);
  EXPECT_NEAR(mc_slope / fd_slope, 1.0, 0.03);
  // The report's sensitivity is the same derivative at the tolerance's size.
  const auto report = study::AnalyseSamples(c, samples);
  const double per_unit = report["sensitivity"][0]["figures"]["ray_error_deg"]["per_unit"].get<double>();
  EXPECT_NEAR(per_unit / fd_slope, 1.0, 0.01);
  EXPECT_EQ(report["ranking"]["ray_error_deg"][0], "lateral_offset");
  // The tolerance the report says keeps the ray error under its limit does (alone).
  const auto& alone = report["limits"]["ray_error_deg"]["alone"]["lateral_offset"];
  EXPECT_NEAR(alone["check"].get<double>(), c.limits.at("ray_error_deg"), 0.02 * c.limits.at("ray_error_deg"));
}

TEST(Tolerance, ShardsMergeToTheStudyOneProcessWrites) {
  const fs::path dir = test::Scratch("tolerance", "shards");
  const std::string base = "-q tolerance -c " + kReference + " -n 60 ";
  ASSERT_EQ(test::Hovs(base + "--out " + (dir / "whole").string()).exit_code, 0);
  std::string shards;
  for (int i = 0; i < 3; ++i) {
    const auto r = test::Hovs(base + "--shard " + std::to_string(i) + "/3 --out " + (dir / std::to_string(i)).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    shards += (dir / std::to_string(i)).string() + " ";
  }
  const auto m = test::Hovs("-q merge " + shards + "--out " + (dir / "merged").string());
  ASSERT_EQ(m.exit_code, 0) << m.output;
  for (const char* f : {"tolerance.json", "samples.csv"})
    EXPECT_EQ(ReadFile(dir / "whole" / f), ReadFile(dir / "merged" / f)) << f;
  EXPECT_TRUE(fs::is_regular_file(dir / "merged" / "index.html"));
  // A shard of another seed does not belong: refused by name, nothing written.
  ASSERT_EQ(test::Hovs(base + "--seed 9 --shard 2/3 --out " + (dir / "other").string()).exit_code, 0);
  const auto bad = test::Hovs("merge " + (dir / "0").string() + " " + (dir / "1").string() + " " +
                              (dir / "other").string() + " --out " + (dir / "bad").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find((dir / "other" / "tolerance.json").string() + ": does not belong"), std::string::npos)
      << bad.output;
  EXPECT_NE(bad.output.find("seed"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(dir / "bad"));
  const auto missing =
      test::Hovs("merge " + (dir / "0").string() + " " + (dir / "1").string() + " --out " + (dir / "bad").string());
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.output.find("shard 2 of 3 is missing"), std::string::npos) << missing.output;
}

TEST(Tolerance, ASampleThatCannotBeEvaluatedCountsAsFailedNeverAsZero) {
  // Errors the unit cannot image its field with: every figure fails (NaN), not 0.
  const ToleranceConfig c = study::LoadToleranceConfig(kReference);
  const study::ToleranceEvaluator ev(c);
  const study::SampleFigures lost = ev.Evaluate(study::SingleError("principal_point", 1e9), {});
  for (int m = 0; m < 4; ++m) EXPECT_TRUE(lost.Failed(m)) << study::Metrics()[m].name << " " << lost.values[m];
  const study::SampleFigures fine = ev.Evaluate(study::SingleError("lateral_offset", 0.05), {});
  for (int m = 0; m < 4; ++m) EXPECT_FALSE(fine.Failed(m)) << study::Metrics()[m].name;
  // Ten samples of which two failed: counted, reported, and the limits' p95 lands on a failure only when more
  // than 5 % fail; then no limit is met, however small the evaluated figures are.
  std::vector<study::Sample> samples(10);
  for (int i = 0; i < 10; ++i) {
    samples[i].index = i;
    samples[i].figures = i < 2 ? lost : fine;
  }
  const nlohmann::json r = study::AnalyseSamples(c, samples);
  for (const auto& m : study::Metrics()) {
    EXPECT_EQ(r["figures"][m.name]["failed"].get<int>(), 2) << m.name;
    EXPECT_EQ(r["figures"][m.name]["evaluated"].get<int>(), 8) << m.name;
    EXPECT_TRUE(r["figures"][m.name]["all_p95"].is_null()) << m.name;
  }
  for (const auto& [name, l] : r["limits"].items()) {
    EXPECT_FALSE(l["meets"].get<bool>()) << name;
    EXPECT_TRUE(l["p95"].is_null()) << name;
  }
  EXPECT_EQ(r["warnings"].size(), 4u);
}

TEST(Tolerance, AMergeVerifiesEveryShardItJoins) {
  const fs::path dir = test::Scratch("tolerance", "tamper");
  const std::string base = "-q tolerance -c " + kReference + " -n 12 ";
  for (int i = 0; i < 2; ++i)
    ASSERT_EQ(
        test::Hovs(base + "--shard " + std::to_string(i) + "/2 --out " + (dir / std::to_string(i)).string()).exit_code,
        0);
  const auto merge = [&]() {
    return test::Hovs("merge " + (dir / "0").string() + " " + (dir / "1").string() + " --out " +
                      (dir / "merged").string());
  };
  const auto refused = [&](const std::string& needle) {
    const auto r = merge();
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "merged"));
  };
  const fs::path csv = dir / "1" / "samples.csv", head = dir / "1" / "tolerance.json";
  const std::string good_csv = ReadFile(csv), good_head = ReadFile(head);
  // An edited figure: the checksum refuses it; with the checksum made again, evaluating the sample again does.
  std::string edited = good_csv;
  const size_t last_comma = edited.rfind(',', edited.size() - 2);
  edited.replace(last_comma + 1, edited.size() - 2 - last_comma, "0.000001");
  WriteFileAtomic(csv, edited);
  refused("does not match its checksum");
  nlohmann::json j = nlohmann::json::parse(good_head);
  j["shard"]["samples_checksum"] = TextChecksum(edited);
  WriteFileAtomic(head, j.dump(1));
  refused("evaluates to");
  WriteFileAtomic(csv, good_csv);
  // Malformed records: a count of 2e9, a string, a seed that is not a number.
  for (const auto& [key, value] :
       std::vector<std::pair<std::string, nlohmann::json>>{{"count", 2000000000}, {"count", "2"}, {"index", -1}}) {
    nlohmann::json k = nlohmann::json::parse(good_head);
    k["shard"][key] = value;
    WriteFileAtomic(head, k.dump(1));
    refused("tolerance.json (shard");
  }
  nlohmann::json seed = nlohmann::json::parse(good_head);
  seed["seed"] = "one";
  WriteFileAtomic(head, seed.dump(1));
  refused("(seed)");
  WriteFileAtomic(head, good_head);
  const auto ok = merge();
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
}

TEST(Tolerance, BadConfigsAreRefusedNamingTheKey) {
  const fs::path dir = test::Scratch("tolerance", "bad");
  fs::create_directories(dir);
  const std::string design = std::string(HOVS_SOURCE_DIR) + "/design/reference.yaml";
  const auto refused = [&](const std::string& yaml, const std::string& needle) {
    WriteFileAtomic(dir / "t.yaml", "design: " + design + "\n" + yaml);
    const auto r = test::Hovs("tolerance -c " + (dir / "t.yaml").string() + " -n 10 --out " + (dir / "out").string());
    EXPECT_EQ(r.exit_code, 2) << yaml << "\n" << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "out"));
  };
  refused("tolerances: {mirror_c: {normal: 0.1}}\n", "unknown parameter 'mirror_c'");
  refused("tolerances: {mirror_a: {normal: 0.1, uniform: 0.1}}\n", "exactly one of normal");
  refused("tolerances: {mirror_a: {gauss: 0.1}}\n", "gauss");
  refused("tolerances: {mirror_a: {normal: -1}}\n", "must be");
  refused("limits: {ray_error: 0.1}\n", "unknown figure 'ray_error'");
  refused("evaluation: {depth_ranges: [0.5]}\n", "twice the baseline");
  refused("seed: -3\n", "seed");
  // Sizes beyond a manufacturing tolerance (they once gave p95 = 0 and "meets" on every limit), a key twice.
  refused("tolerances: {principal_point: {normal: 1.0e9}}\n", "is not a manufacturing tolerance");
  refused("tolerances: {rim_diameter: {uniform: 10000}}\n", "5 % of the nominal rim diameter");
  refused("tolerances: {mirror_a: {normal: 0.01}, mirror_a: {normal: 0.02}}\n", "duplicate key 'mirror_a'");
  refused("limits: {ray_error_deg: 0.1, ray_error_deg: 0.2}\n", "given twice");
  WriteFileAtomic(dir / "t.yaml", "tolerances: {}\n");
  const auto r = test::Hovs("tolerance -c " + (dir / "t.yaml").string() + " --out " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("needs 'design'"), std::string::npos) << r.output;
  const auto shards = test::Hovs("tolerance -c " + kReference + " -n 2 --shard 0/3 --out " + (dir / "out").string());
  EXPECT_EQ(shards.exit_code, 2);
  EXPECT_NE(shards.output.find("--shard"), std::string::npos) << shards.output;
}

}  // namespace
}  // namespace hovs
