// Datasets and the render/dataset commands: manifest, files, ground truth of every frame; bad input through
// the command line leaves nothing behind.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <OpenEXR/OpenEXRConfig.h>
#include <OpenImageIO/oiioversion.h>

#include "calib/checkerboard_detector.h"
#include "core/io.h"
#include "raytrace/render.h"
#include "scenes/dataset.h"
#include "tests/cli_helper.h"
#include "tests/raytrace/small_scene.h"
#include "io/image_io.h"

namespace hovs {
namespace {
namespace fs = std::filesystem;

TEST(Dataset, BoardPosesAreSeededAndKeepEveryCornerVisible) {
  const auto cfg = test::SmallCalibrationScene();
  scenes::DatasetOptions o;
  o.count = 5;
  o.seed = 42;
  const auto a = scenes::DrawBoardPoses(cfg, o), b = scenes::DrawBoardPoses(cfg, o);
  o.seed = 43;
  const auto c = scenes::DrawBoardPoses(cfg, o);
  ASSERT_EQ(a.size(), 5u);
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ((a[i].translation - b[i].translation).norm(), 0.0);
  EXPECT_GT((a[0].translation - c[0].translation).norm(), 1e-6);
}

TEST(Dataset, StereoBoardPosesStayAboveTheGround) {
  // The stereo set's 1.2 m board at 1.5-3.5 m and 6-35 deg below the 1.3 m high units: its centre may fall below
  // the ground (as 7 of 12 poses did at seed 1 before boards were kept clear of the scene), the board itself not.
  const auto cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_stereo.yaml");
  auto o = scenes::DatasetOptions::ForKind("stereo_aruco");
  o.count = 12;
  int low = 0;
  for (uint64_t seed : {1, 2}) {
    o.seed = seed;
    const auto poses = scenes::DrawBoardPoses(cfg, o);
    ASSERT_EQ(poses.size(), 12u);
    const double hw = 0.5 * o.board.Width(), hh = 0.5 * o.board.Height();
    for (const auto& p : poses) {
      double lowest = INFINITY;
      for (double x : {-hw, hw})
        for (double y : {-hh, hh}) lowest = std::min(lowest, (p * Vec3d(x, y, 0)).z());
      EXPECT_GT(lowest, 0.0) << "seed " << seed << ": the board goes " << -lowest << " m into the ground";
      low += lowest < 0.3;  // boards still come down near the ground (the sampler is not just confined high up)
    }
  }
  EXPECT_GT(low, 0);
}

TEST(Dataset, DepthSequenceMovesTheRigAndItsGroundTruth) {
  // The street's two-unit rig at a tenth of the resolution, 3 frames, 0.7 m per frame along +y, turning.
  auto cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/street.yaml");
  scenes::DownscaleCameras(&cfg, 10);
  cfg.render.samples = 1;
  cfg.render.truth_file.groups = raytrace::TruthFileOptions::AllGroups();  // P is checked against Z
  auto o = scenes::DatasetOptions::ForKind("depth_sequence");
  o.count = 3, o.step_m = 0.7, o.heading_deg = 90, o.yaw_step_deg = 5;
  const fs::path out = test::Scratch("dataset", "depth-seq");
  scenes::WriteDepthSequence(cfg, o, out, {{"hovs", "test"}});
  const auto m = nlohmann::json::parse(ReadFile(out / "dataset.json"));
  EXPECT_EQ(m["kind"], "depth_sequence");
  ASSERT_EQ(m["frames"].size(), 3u);
  const size_t n_units = cfg.description.units.size();
  ASSERT_EQ(n_units, 2u);
  for (int k = 0; k < 3; ++k) {
    const auto& fr = m["frames"][k];
    ASSERT_EQ(fr["views"].size(), n_units);
    const Rigid3d world_from_rig = scenes::WorldFromRigAt(cfg, o, k);
    // The rig's centroid moves by k x 0.7 m along +y (it turns about itself).
    Vec3d c0 = Vec3d::Zero(), ck = Vec3d::Zero();
    for (const auto& u : cfg.description.units)
      c0 += u.world_from_mirror.translation, ck += world_from_rig * u.world_from_mirror.translation;
    EXPECT_NEAR(((ck - c0) / 2.0 - Vec3d(0, 0.7 * k, 0)).norm(), 0.0, 1e-9);
    for (size_t u = 0; u < n_units; ++u) {
      const auto& v = fr["views"][u];
      // Ground truth of that frame: every world point P in the range channel lies at range Z from the moved
      // viewpoint, so the truth follows the rig.
      const Vec3d viewpoint = world_from_rig * cfg.description.units[u].world_from_mirror.translation;
      const auto exr = io::ReadExr(out / v["ground_truth"]["exr"].get<std::string>());
      const auto &Z = exr.at("Z"), &X = exr.at("P.X"), &Y = exr.at("P.Y"), &W = exr.at("P.Z"), &mask = exr.at("mask");
      int checked = 0;
      double worst = 0;
      for (size_t i = 0; i < Z.size(); i += 7) {
        if (mask[i] < 0.5 || !std::isfinite(Z[i])) continue;
        const double r = (Vec3d(X[i], Y[i], W[i]) - viewpoint).norm();
        worst = std::max(worst, std::abs(r - Z[i]) / Z[i]);
        ++checked;
      }
      EXPECT_GT(checked, 500);
      EXPECT_LT(worst, 1e-5) << "frame " << k << " unit " << u;
    }
  }
  fs::remove_all(out.parent_path());
}

TEST(Dataset, ADepthSequenceDrivenIntoAnObjectIsRefusedBeforeRendering) {
  // The street's rig heading 45 degrees at 1.5 m per frame: at frame 2 the left unit is inside the parked car
  // (4.2 x 1.8 x 1.4 m at (3.0, 2.8)). One error naming the frame and the car; no output folder.
  auto cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/street.yaml");
  scenes::DownscaleCameras(&cfg, 10);
  auto o = scenes::DatasetOptions::ForKind("depth_sequence");
  o.count = 4, o.step_m = 1.5, o.heading_deg = 45;
  const fs::path out = test::Scratch("dataset", "depth-seq-crash");
  try {
    scenes::WriteDepthSequence(cfg, o, out, {{"hovs", "test"}});
    ADD_FAILURE() << "the sequence was rendered";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("depth_sequence frame 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'parked_car'"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(out));
  o.count = 2;  // frames 0 and 1 stay clear of it
  EXPECT_NO_THROW(scenes::WriteDepthSequence(cfg, o, out, {{"hovs", "test"}}));
}

TEST(Dataset, CalibrationSetHasManifestImagesAndGroundTruth) {
  auto cfg = test::SmallCalibrationScene();
  cfg.render.truth_file.groups = raytrace::TruthFileOptions::AllGroups();
  scenes::DatasetOptions o;
  o.count = 3;
  const fs::path out = test::Scratch("dataset", "calib");
  scenes::WriteCalibrationDataset(cfg, o, out, {{"hovs", "test"}});
  const auto m = nlohmann::json::parse(ReadFile(out / "dataset.json"));
  EXPECT_EQ(m["format"], "hovs-dataset");
  EXPECT_EQ(m["kind"], "mono_calibration");
  EXPECT_EQ(m["seed"], 1);
  ASSERT_EQ(m["frames"].size(), 3u);
  EXPECT_EQ(m["boards"][0]["inner_corners"], nlohmann::json({7, 5}));
  for (const auto& fr : m["frames"]) {
    const auto& v = fr["views"][0];
    int w = 0, h = 0, ch = 0;
    io::ReadImage(out / v["image"].get<std::string>(), &w, &h, &ch);
    EXPECT_EQ(w, 688);
    EXPECT_EQ(h, 550);
    const auto side = nlohmann::json::parse(ReadFile(out / v["ground_truth"]["sidecar"].get<std::string>()));
    EXPECT_EQ(side["boards"][0]["visible_corners"], 35);
    const auto exr = io::ReadExr(out / v["ground_truth"]["exr"].get<std::string>());
    EXPECT_EQ(exr.width, 688);
    for (const char* name : {"Z", "P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z", "id", "mask", "M.X", "M.Y", "M.Z"})
      EXPECT_EQ(exr.at(name).size(), 688u * 550u) << name;
    EXPECT_EQ(exr.attributes.at("hovs:unit"), "unit0");
    // Each visible corner's pixel has the board's id in the id channel.
    const int board_id = side["boards"][0]["object_id"];
    for (const auto& c : side["boards"][0]["corners"]) {
      const int x = static_cast<int>(std::lround(c["pixel"][0].get<double>()));
      const int y = static_cast<int>(std::lround(c["pixel"][1].get<double>()));
      EXPECT_EQ(static_cast<int>(exr.at("id")[static_cast<size_t>(y) * 688 + x]), board_id);
    }
  }
  fs::remove_all(out.parent_path());
}

TEST(Dataset, StereoArucoPairsSeeTheBoardFromBothUnits) {
  auto cfg = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_stereo.yaml");
  for (auto& u : cfg.description.units)
    u.rig.camera = PinholeCamera<double>::FromPhysical(0.016, 4 * 4.54e-6, 688, 550);
  cfg.render.samples = 1;
  scenes::DatasetOptions o = scenes::DatasetOptions::ForKind("stereo_aruco");
  o.count = 2;
  o.edge_margin_px = 2;
  const fs::path out = test::Scratch("dataset", "stereo");
  scenes::WriteCalibrationDataset(cfg, o, out, {{"hovs", "test"}});
  const auto m = nlohmann::json::parse(ReadFile(out / "dataset.json"));
  EXPECT_EQ(m["kind"], "stereo_aruco");
  EXPECT_EQ(m["units"].size(), 2u);
  EXPECT_EQ(m["boards"][0]["type"], "aruco");
  EXPECT_NEAR(m["boards"][0]["width"].get<double>(), 1.24, 1e-12);
  ASSERT_EQ(m["frames"].size(), 2u);
  for (const auto& fr : m["frames"]) {
    ASSERT_EQ(fr["views"].size(), 2u);
    EXPECT_EQ(fr["views"][0]["unit"], "left");
    EXPECT_EQ(fr["views"][1]["unit"], "right");
    for (const auto& v : fr["views"]) {
      const auto side = nlohmann::json::parse(ReadFile(out / v["ground_truth"]["sidecar"].get<std::string>()));
      EXPECT_EQ(side["boards"][0]["corners"].size(), 100u);
      EXPECT_GE(side["boards"][0]["visible_corners"].get<int>(), 60) << v["image"];
    }
  }
  o.kind = "stereo_aruco";
  auto mono = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_calibration.yaml");
  EXPECT_THROW(scenes::DrawBoardPoses(mono, o), Error) << "a stereo set needs two units";
  fs::remove_all(out.parent_path());
}

TEST(Dataset, ASetRenderedWithoutGroundTruthHasAManifestAndAReport) {
  // render.ground_truth: false (as real captures have none): the report page used to read every view's sidecar
  // and stopped with an uncaught JSON error (exit 3).
  auto cfg = test::SmallCalibrationScene();
  cfg.render.ground_truth = false;
  scenes::DatasetOptions o;
  o.count = 2;
  const fs::path dir = test::Scratch("dataset", "no-truth");
  ASSERT_NO_THROW(scenes::WriteCalibrationDataset(cfg, o, dir / "set", {{"hovs", "test"}}));
  const auto m = nlohmann::json::parse(ReadFile(dir / "set" / "dataset.json"));
  ASSERT_EQ(m["frames"].size(), 2u);
  for (const auto& fr : m["frames"])
    for (const auto& v : fr["views"]) {
      EXPECT_FALSE(v.contains("ground_truth")) << v.dump();
      EXPECT_TRUE(fs::exists(dir / "set" / v["image"].get<std::string>()));
    }
  EXPECT_FALSE(fs::exists(dir / "set" / "truth"));
  EXPECT_NE(ReadFile(dir / "set" / "index.html").find("no ground truth"), std::string::npos);
}

TEST(Detection, EveryViewOfAHalfResolutionSetIsDetectedWhole) {
  // The reference calibration set at 1375 x 1100 and 2 samples per pixel (CalibrateCli's detection set), render
  // seed 16: view 7's board has squares of about 15 px, and its last column used to be lost (6 x 5 of 7 x 5): the
  // grid's quadratic extrapolation multiplied the candidates' half-pixel error beyond its search radius.
  auto half = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_calibration.yaml");
  half.description.units[0].rig.camera = PinholeCamera<double>::FromPhysical(0.016, 2 * 4.54e-6, 1375, 1100);
  half.render.samples = 2;
  half.render.seed = 16;
  scenes::DatasetOptions o;
  o.count = 9;
  const fs::path dir = test::Scratch("detection", "seed16");
  scenes::WriteCalibrationDataset(half, o, dir / "set", {{"hovs", "test"}});
  calib::CheckerboardDetectOptions opts;
  opts.board = {7, 5, 0.03};
  int views = 0;
  for (int k = 0; k < 9; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "unit0_%04d.png", k);
    int w = 0, h = 0, c = 0;
    const auto px = io::ReadImage(dir / "set" / "images" / name, &w, &h, &c);
    cv::Mat grey(h, w, CV_8UC1);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const float* p = &px[(static_cast<size_t>(y) * w + x) * c];
        const float g = c >= 3 ? 0.299f * p[0] + 0.587f * p[1] + 0.114f * p[2] : p[0];
        grey.at<unsigned char>(y, x) = static_cast<unsigned char>(std::clamp(g * 255.0f + 0.5f, 0.0f, 255.0f));
      }
    const auto det = calib::DetectCheckerboard(grey, opts);
    EXPECT_TRUE(det.complete) << name << ": " << det.status;
    ++views;
  }
  EXPECT_EQ(views, 9);
}

TEST(CalibrateCli, CalibratesASyntheticSetAgainstGroundTruthAndRejectsBadInput) {
  const auto cfg = test::SmallCalibrationScene();
  scenes::DatasetOptions o;
  o.count = 9;
  const fs::path dir = test::Scratch("calibrate-cli", "work");
  scenes::WriteCalibrationDataset(cfg, o, dir / "set", {{"hovs", "test"}});
  // The solver alone, on the exact corners.
  const auto ok = test::Hovs("-q calibrate --truth-corners --dataset " + (dir / "set" / "dataset.json").string() +
                             " --out " + (dir / "cal").string());
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  const auto j = nlohmann::json::parse(ReadFile(dir / "cal" / "calibration.json"));
  EXPECT_LT(j["polynomial"]["rms_px"].get<double>(), 0.01);
  EXPECT_LT(j["ground_truth"]["mean_ray_angle_deg"].get<double>(), 0.01);
  EXPECT_EQ(j["order_selection"].size(), 5u);
  // Detection + calibration on the images, at half the resolution (1375 x 1100, squares of 20-55 px) and 2
  // samples per pixel.
  auto half = scenes::LoadSceneConfig(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_calibration.yaml");
  half.description.units[0].rig.camera = PinholeCamera<double>::FromPhysical(0.016, 2 * 4.54e-6, 1375, 1100);
  half.render.samples = 2;
  scenes::WriteCalibrationDataset(half, o, dir / "half", {{"hovs", "test"}});
  const auto det = test::Hovs("-q calibrate --dataset " + (dir / "half" / "dataset.json").string() + " --out " +
                              (dir / "cal-det").string());
  ASSERT_EQ(det.exit_code, 0) << det.output;
  const auto jd = nlohmann::json::parse(ReadFile(dir / "cal-det" / "calibration.json"));
  ASSERT_EQ(jd["detection"].size(), 9u);
  EXPECT_TRUE(fs::exists(dir / "cal-det" / "figures" / "unit0_0000.png"));  // reprojection plot per image
  for (const auto& d : jd["detection"]) EXPECT_TRUE(d["complete"].get<bool>()) << d.dump();
  std::printf(
      "[ figure ] 1375 x 1100, 2 spp: detection RMS %.3f px from the exact corners, calibration RMS %.3f px, "
      "mean ray angle %.4f deg\n",
      jd["detection_rms_to_truth_px"].get<double>(), jd["polynomial"]["rms_px"].get<double>(),
      jd["ground_truth"]["mean_ray_angle_deg"].get<double>());
  EXPECT_LT(jd["detection_rms_to_truth_px"].get<double>(), 0.3);
  EXPECT_LT(jd["polynomial"]["rms_px"].get<double>(), 0.3);
  EXPECT_TRUE(fs::exists(dir / "cal-det" / "figures" / "error_map.png"));
  EXPECT_TRUE(jd["polynomial"]["outliers"].is_array());
  // The unified model's OpenCV YAML is a model file for the other commands: a panorama through it.
  const std::string unified_yaml = ReadFile(dir / "cal-det" / "unified.yaml");
  EXPECT_NE(unified_yaml.find("camera_matrix"), std::string::npos);
  EXPECT_NE(unified_yaml.find("distortion_coefficients"), std::string::npos);
  const auto pano =
      test::Hovs("-q unwrap --model " + (dir / "cal-det" / "unified.yaml").string() + " --layout panorama -i " +
                 (dir / "half" / "images").string() + " -o " + (dir / "pano").string());
  ASSERT_EQ(pano.exit_code, 0) << pano.output;
  EXPECT_NE(ReadFile(dir / "pano" / "views.json").find("unified"), std::string::npos);
  // Visual positioning on one of the images: the unit is aligned, so the camera sits at the design's focus.
  const auto first_image = (dir / "half" / jd["detection"][0]["image"].get<std::string>()).string();
  const auto pos = test::Hovs("-q position -i " + first_image + " --design " +
                              (dir / "half" / "dataset.json").string() + " -o " + (dir / "pos").string());
  ASSERT_EQ(pos.exit_code, 0) << pos.output;
  const auto jp = nlohmann::json::parse(ReadFile(dir / "pos" / "position.json"));
  for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(jp["camera_offset_mm"][k].get<double>()), 0.02) << jp.dump();
  const auto pos_bad = test::Hovs("position -i " + first_image + " --design " +
                                  (dir / "set" / "dataset.json").string() + " -o " + (dir / "pos-bad").string());
  EXPECT_EQ(pos_bad.exit_code, 2);
  EXPECT_NE(pos_bad.output.find("but the design's camera is 688x550"), std::string::npos) << pos_bad.output;
  EXPECT_FALSE(fs::exists(dir / "pos-bad"));
  // Bad input: one clear error, exit 2, no report.
  const auto rejected = [&](const std::string& args, const std::string& needle) {
    const auto r = test::Hovs("calibrate " + args + " --out " + (dir / "bad").string());
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "bad"));
  };
  const std::string vmr = std::string(HOVS_SHARED_DIR) + "/data/vmr/reference_corners.csv";
  rejected("--corners " + vmr + " --size 1024by768", "expected WxH");
  rejected("--corners " + vmr + " --size 640x480", "lies outside the 640x480 image");
  rejected("--corners " + vmr + " --size 1024x768 --dataset x.json",
           "exactly one of --corners, --dataset and --images");
  rejected("--images " + (dir / "set" / "images").string(), "needs --board");
  rejected("--images " + (dir / "set" / "images").string() + " --board 5x4x0.03", "larger than the 5x4 board");
  rejected("--images " + (dir / "set" / "images").string() + " --board 7x5", "expected COLSxROWSxSQUARE");
  rejected("--images " + (dir / "set" / "images").string() + " --board 7x5x0.03x9", "expected COLSxROWSxSQUARE");
  rejected("--corners " + vmr + " --size 1024x768x2", "expected WxH");
  rejected("--corners " + vmr + " --size 1024x768 --corner-noise 0.5", "needs --truth-corners");  // was ignored
  // A corrupt ground-truth sidecar: named (it was an uncaught JSON exception, exit 3).
  fs::copy(dir / "set", dir / "set-bad", fs::copy_options::recursive);
  const auto sidecars = nlohmann::json::parse(ReadFile(dir / "set-bad" / "dataset.json"));
  WriteFileAtomic(dir / "set-bad" / sidecars["frames"][0]["views"][0]["ground_truth"]["sidecar"].get<std::string>(),
                  "{bad");
  // The damaged sidecar is caught by its checksum before it is parsed.
  rejected("--truth-corners --dataset " + (dir / "set-bad" / "dataset.json").string(), "does not match its checksum");
  rejected("--truth-corners --dataset " + (dir / "set" / "dataset.json").string() + " --corner-noise -1",
           "--corner-noise");
  rejected("--images " + (dir / "set" / "images").string() + " --board 7x5x0.03 --corner-refinement sharp",
           "corner_refinement must be 'edges' or 'subpix'");
  rejected("--corners /nonexistent.csv --size 1024x768", "/nonexistent.csv: file not found");
  std::ofstream(dir / "two.csv") << "image,corner,board_x_mm,board_y_mm,u_px,v_px\n"
                                 << "a.png,0,0,0,100,100\na.png,1,30,0,110,100\nb.png,0,0,0,200,200\n";
  rejected("--corners " + (dir / "two.csv").string() + " --size 1024x768", "needs at least three images");
  fs::remove_all(dir.parent_path());
}

// A camera unlike the reference unit (scenes/stress_parabolic.yaml): near-parabolic mirror (xi = 0.994) whose
// field reaches +30 degrees, 640 x 480, a 7 x 11-corner board of 30 mm squares (6 to 20 px) held below and
// above the horizon. Every calibration completes: on the exact corners with 0.05 px noise at the noise floor
// (0.071 px), and from hovs' own detection.
TEST(CalibrateCli, ANearParabolicSmallCameraWithAFieldAboveTheHorizonCalibrates) {
  const fs::path dir = test::Scratch("calibrate-cli", "stress");
  const std::string scene = std::string(HOVS_SOURCE_DIR) + "/scenes/stress_parabolic.yaml";
  const auto set =
      test::Hovs("-q dataset --scene " + scene + " --board 7x11x0.03 --elevation -30 25 --distance 0.35 0.8 -n 16 -o " +
                 (dir / "set").string());
  ASSERT_EQ(set.exit_code, 0) << set.output;
  const std::string manifest = (dir / "set" / "dataset.json").string();
  const auto noisy =
      test::Hovs("-q calibrate --truth-corners --corner-noise 0.05 --seed 3 --cross-validate 4 --dataset " + manifest +
                 " --out " + (dir / "noisy").string());
  ASSERT_EQ(noisy.exit_code, 0) << noisy.output;
  const auto jn = nlohmann::json::parse(ReadFile(dir / "noisy" / "calibration.json"));
  EXPECT_LT(jn["polynomial"]["rms_px"].get<double>(), 0.1);
  EXPECT_LT(jn["unified"]["rms_px"].get<double>(), 0.1);
  EXPECT_LT(jn["ground_truth"]["mean_ray_angle_deg"].get<double>(), 0.08);
  EXPECT_LT(jn["polynomial"]["inverse"]["max_error_px"].get<double>(), 0.05);
  // Cross-validation: held-out boards at the noise level; the folds' models within a tenth of a pixel.
  const auto& cv = jn["cross_validation"];
  EXPECT_EQ(cv["folds"], 4);
  EXPECT_LT(cv["held_out_rms_px"].get<double>(), 0.1);
  EXPECT_GT(cv["held_out_rms_px"].get<double>(), cv["train_rms_px"].get<double>());
  EXPECT_LT(cv["spread"]["px"]["median"].get<double>(), 0.1);
  EXPECT_TRUE(fs::exists(dir / "noisy" / "figures" / "cross_validation_px.png"));
  // hovs compare: the calibrated polynomial against the true rig, as calibrate's own ground-truth figure.
  const auto cmp = test::Hovs("-q compare " + manifest + " " + (dir / "noisy" / "calibration.json").string() +
                              " --kind-b polynomial --out " + (dir / "cmp").string());
  ASSERT_EQ(cmp.exit_code, 0) << cmp.output;
  const auto jc = nlohmann::json::parse(ReadFile(dir / "cmp" / "compare.json"));
  EXPECT_LT(jc["diff"]["deg"]["median"].get<double>(), 0.08);
  EXPECT_NEAR(jc["diff"]["rotation_deg"].get<double>(), jn["ground_truth"]["frame_rotation_deg"].get<double>(), 1e-3);
  EXPECT_TRUE(fs::exists(dir / "cmp" / "figures" / "diff_px.png"));
  const auto refused = [&](const std::string& args, const std::string& needle) {
    const auto r = test::Hovs(args + " --out " + (dir / "bad").string());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "bad"));
  };
  refused("compare " + manifest + " " + std::string(HOVS_SOURCE_DIR) + "/scenes/reference_calibration.yaml",
          "is a model of 2750x2200 images but A");
  refused("compare " + manifest + " " + manifest + " --kind-b sideways", "expected auto, physical, polynomial");
  refused("compare " + manifest + " " + manifest + " --kind-b physical", "has no physical model");
  refused("calibrate --truth-corners --dataset " + manifest + " --cross-validate 1", "needs at least 2 folds");
  refused("calibrate --truth-corners --dataset " + manifest + " --cross-validate 17",
          "more folds (17) than images (16)");
  const auto det = test::Hovs("-q calibrate --dataset " + manifest + " --out " + (dir / "det").string());
  ASSERT_EQ(det.exit_code, 0) << det.output;
  const auto jd = nlohmann::json::parse(ReadFile(dir / "det" / "calibration.json"));
  int found = 0;
  for (const auto& d : jd["detection"]) found += d["found"].get<bool>();
  std::printf(
      "[ figure ] stress set: %d of 16 boards, detection RMS %.3f px, polynomial %.3f px, unified %.3f px, "
      "mean ray angle %.4f deg\n",
      found, jd["detection_rms_to_truth_px"].get<double>(), jd["polynomial"]["rms_px"].get<double>(),
      jd["unified"]["rms_px"].get<double>(), jd["ground_truth"]["mean_ray_angle_deg"].get<double>());
  EXPECT_GE(found, 10);
  EXPECT_LT(jd["detection_rms_to_truth_px"].get<double>(), 0.15);
  EXPECT_LT(jd["polynomial"]["rms_px"].get<double>(), 0.15);
  EXPECT_LT(jd["ground_truth"]["mean_ray_angle_deg"].get<double>(), 0.1);
  // Bad input from image folders: one clear error each, exit 2, nothing written.
  const auto rejected = [&](const fs::path& images, const std::string& board, const std::string& needle) {
    const auto r =
        test::Hovs("calibrate --images " + images.string() + " --board " + board + " --out " + (dir / "bad").string());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(fs::exists(dir / "bad"));
  };
  const fs::path first = dir / "set" / jd["detection"][0]["image"].get<std::string>();
  fs::create_directories(dir / "one");
  fs::copy_file(first, dir / "one" / "a.png");
  rejected(dir / "one", "7x11x0.03", "only 1 of 1 images have a usable board (at least 3 needed)");
  fs::create_directories(dir / "sizes");
  for (const auto& d : jd["detection"]) {
    const fs::path image = dir / "set" / d["image"].get<std::string>();
    fs::copy_file(image, dir / "sizes" / image.filename());
  }
  fs::copy_file(std::string(HOVS_SOURCE_DIR) + "/tests/data/golden_reference_board.png",
                dir / "sizes" / "zz_other.png");
  rejected(dir / "sizes", "7x11x0.03", "differs from the first image's 640x480");
  rejected(dir / "set" / "images", "5x4x0.03", "the board description does not match the image");
  fs::create_directories(dir / "empty");
  std::ofstream(dir / "empty" / "notes.txt") << "no images here\n";
  rejected(dir / "empty", "7x11x0.03", "the folder holds no images");
  fs::remove_all(dir);
}

TEST(RenderCli, RendersAndRejectsBadInput) {
  const fs::path dir = test::Scratch("render-cli", "work");
  fs::create_directories(dir);
  // A small scene: reference unit at low resolution, one board.
  std::string scene = ReadFile(std::string(HOVS_SOURCE_DIR) + "/scenes/reference_board.yaml");
  const std::string cam =
      "camera: {focal_length: 0.016, pixel_pitch: 4.54e-6, width: 2750, height: 2200, lens_aperture: 0.020}";
  scene.replace(scene.find(cam), cam.size(),
                "camera: {focal_length: 0.016, pixel_pitch: 3.632e-5, width: 344, height: 275, lens_aperture: 0.020}");
  std::ofstream(dir / "small.yaml") << scene;
  const auto ok = test::Hovs("-q render --scene " + (dir / "small.yaml").string() + " --out " + (dir / "out").string() +
                             " --samples 1");
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_TRUE(fs::is_regular_file(dir / "out" / "dataset.json"));
  EXPECT_TRUE(fs::is_regular_file(dir / "out" / "truth" / "unit0.exr"));
  {
    // The manifest names every library the render and its later stages depend on, at the versions built with.
    const auto versions = nlohmann::json::parse(ReadFile(dir / "out" / "dataset.json"))["versions"];
    EXPECT_EQ(versions.value("embree", ""), RTC_VERSION_STRING);
    EXPECT_EQ(versions.value("opencv", ""), CV_VERSION);
    EXPECT_EQ(versions.value("openimageio", ""), std::to_string(OIIO_VERSION_MAJOR) + "." +
                                                     std::to_string(OIIO_VERSION_MINOR) + "." +
                                                     std::to_string(OIIO_VERSION_PATCH));
    EXPECT_EQ(versions.value("openexr", ""), OPENEXR_VERSION_STRING);
    EXPECT_NE(versions.value("aravis", ""), "") << versions;
  }

  const auto rejected = [&](const std::string& yaml, const std::string& needle, const std::string& extra = "") {
    std::ofstream(dir / "bad.yaml") << yaml;
    const auto r =
        test::Hovs("render --scene " + (dir / "bad.yaml").string() + " --out " + (dir / "bad_out").string() + extra);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "bad_out"));
  };
  rejected(scene + "fog: true\n", "unknown key 'fog'");
  rejected(scene + "render: {samples: 0}\n", "duplicate key 'render'");
  std::string zero = scene;
  zero.replace(zero.find("render: {samples: 16"), 20, "render: {samples: 0");
  rejected(zero, "samples");
  rejected(scene, "samples", " --samples -3");
  // Zero given on the command line is not "the scene's value" (it used to render with the scene's samples).
  rejected(scene, "--samples", " --samples 0");
  rejected(scene, "--seed", " --seed -1");
  std::string far = scene;
  far.replace(far.find("position: [0, 0, 1.3]"), 21, "position: [0, 0, 1e300]");  // an Embree assertion once
  rejected(far, "from the world origin");
  std::string huge = scene;
  huge.replace(huge.find("squares: [8, 6]"), 15, "squares: [800000, 600000]");  // std::bad_alloc once
  rejected(huge, "at most 1000 x 1000");
  // An aperture of 1e300 m put ray origins at infinity (an Embree assertion); a unit may not outrun the world.
  std::string lens = scene;
  lens.replace(lens.find("lens_aperture: 0.020}"), 21, "lens_aperture: 0.020, lens: {aperture_diameter: 1e300}}");
  rejected(lens, "aperture_diameter");
  std::string fast = scene;
  fast.replace(fast.find("pose: {position: [0, 0, 1.3]}"), 29,
               "pose: {position: [0, 0, 1.3]}\n    velocity: [1e300, 0, 0]");
  rejected(fast, "at most 1000 m/s");
  std::string away = scene;
  away.replace(away.find("pose: {position: [0, 0, 1.3]}"), 29,
               "pose: {position: [9990, 0, 1.3]}\n    velocity: [900, 0, 0]");
  away.replace(away.find("render: {samples: 16"), 20, "render: {exposure_time: 1, samples: 16");
  rejected(away, "during the exposure");
  std::string pitch = scene;
  pitch.replace(pitch.find("pixel_pitch: 3.632e-5"), 21, "pixel_pitch: 1e-300");
  rejected(pitch, "pixel_pitch");
  const auto no_frames =
      test::Hovs("dataset --scene " + (dir / "small.yaml").string() + " -n 0 --out " + (dir / "bad_out").string());
  EXPECT_EQ(no_frames.exit_code, 2) << no_frames.output;
  EXPECT_NE(no_frames.output.find("--count"), std::string::npos) << no_frames.output;
  EXPECT_FALSE(fs::exists(dir / "bad_out"));
  std::string inside = scene;
  inside.insert(inside.find("    pose: {position: [0, 0, 1.3]}"), "    misalignment: {height_error: -0.2}\n");
  rejected(inside, "inside the mirror");
  std::string missing = scene;
  missing.replace(missing.find("texture: {noise: {scale: 0.03"), 29,
                  "texture: {image: {path: gone.png, width: 1, height: 1}, noise: {scale: 0.03");
  rejected(missing, "exactly one of");
  const auto nofile =
      test::Hovs("render --scene " + (dir / "nope.yaml").string() + " --out " + (dir / "bad_out").string());
  EXPECT_EQ(nofile.exit_code, 2);
  EXPECT_NE(nofile.output.find("scene file not found"), std::string::npos);
  fs::remove_all(dir.parent_path());
}

}  // namespace
}  // namespace hovs
