// Other tools' camera models and files: the generic models against the unified one where they coincide, refits,
// Kalibr's camchain and the MEI YAML read back as written, and bad files refused by name.
#include <gtest/gtest.h>

#include "calib/camera_formats.h"
#include "calib/model_refit.h"
#include "core/error.h"

namespace hovs::calib {
namespace {

UnifiedModel<double> Camera(double xi) {
  UnifiedModel<double> u;
  u.xi = xi, u.fx = 300, u.fy = 298, u.cx = 511.3, u.cy = 383.8, u.width = 1024, u.height = 768;
  return u;
}

// EUCM with beta = 1 and DS with xi = 0 are the unified model: alpha = xi_u / (1 + xi_u), f = f_u / (1 + xi_u).
TEST(GenericModels, ReduceToTheUnifiedModel) {
  const UnifiedModel<double> u = Camera(0.9);
  const double a = u.xi / (1 + u.xi);
  GenericModel<double> eucm, ds;
  eucm.kind = GenericKind::kEucm, ds.kind = GenericKind::kDoubleSphere;
  eucm.p = {a, 1.0, u.fx / (1 + u.xi), u.fy / (1 + u.xi), u.cx, u.cy, 0, 0};
  ds.p = {0.0, a, u.fx / (1 + u.xi), u.fy / (1 + u.xi), u.cx, u.cy, 0, 0};
  for (const Vec3d& m : {Vec3d(0.3, -0.2, -1), Vec3d(1, 0.5, -0.2), Vec3d(-0.7, 0.9, 0.1), Vec3d(0, 0, -1)}) {
    Vec2d q_u, q_e, q_d;
    ASSERT_TRUE(u.ImgFromCam(m, &q_u));
    ASSERT_TRUE(eucm.ImgFromCam(OmniFromMirror(m), &q_e));
    ASSERT_TRUE(ds.ImgFromCam(OmniFromMirror(m), &q_d));
    EXPECT_LT((q_e - q_u).norm(), 1e-9) << m.transpose();
    EXPECT_LT((q_d - q_u).norm(), 1e-9) << m.transpose();
  }
}

TEST(ModelRefit, FitsAUnifiedCameraExactlyAndReportsKannalaBrandtsCost) {
  const AnyModel source = AnyModel::Unified(Camera(0.9), 60, 380);
  RefitOptions o;
  for (const char* kind : {"ds", "eucm", "omni", "kb"}) {
    o.kind = kind;
    const Refit r = RefitModel(source, o);
    EXPECT_TRUE(r.converged) << kind;
    EXPECT_GT(r.pixels, 1000u);
    EXPECT_EQ(r.outside, 0u) << kind;
    EXPECT_GT(r.field_deg, 90) << "the field reaches above the horizon";
    if (std::string(kind) == "kb")
      EXPECT_LT(r.px.max, 2.0) << "an approximation of the unified model, its cost reported";
    else
      EXPECT_LT(r.px.max, 1e-3) << kind << " represents the unified model exactly";
  }
  o.kind = "fisheye";
  EXPECT_THROW(RefitModel(source, o), Error);
}

TEST(CameraFormats, KalibrCamchainAndMeiReadBackAsWritten) {
  const UnifiedModel<double> u = [] {
    auto m = Camera(1.1);
    m.distortion = {0.07, -0.01, 1e-4, -2e-4};
    return m;
  }();
  KalibrCamera c0 = KalibrFromUnified(u), c1 = KalibrFromUnified(Camera(0.8));
  const Rigid3d right_from_left(Eigen::Quaterniond(Eigen::AngleAxisd(0.02, Vec3d(0.3, 1, 0.1).normalized())),
                                Vec3d(-0.64, 0.007, 0.014));
  c1.T_cn_cnm1 = ToolsFromMirrorPose(right_from_left);
  const Eigen::Matrix3d R = c1.T_cn_cnm1->topLeftCorner(3, 3);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12) << "a proper rotation";
  EXPECT_NEAR((*c1.T_cn_cnm1)(2, 3), -0.014, 1e-15) << "z flips with the frame";
  // With refitted frames turned about their axes: the pose maps the left tools' coordinates of a point to the
  // right tools' ones.
  const double gl = 0.01, gr = -0.02;
  const Eigen::Matrix4d M = ToolsFromMirrorPose(right_from_left, gl, gr);
  const Vec3d P(1.2, -0.4, -0.8);
  const auto tools = [](const Vec3d& m, double g) {
    return Vec3d(Eigen::AngleAxisd(g, Vec3d::UnitZ()) * OmniFromMirror(m));
  };
  const Vec3d mapped = M.topLeftCorner<3, 3>() * tools(P, gl) + M.topRightCorner<3, 1>();
  EXPECT_LT((mapped - tools(right_from_left * P, gr)).norm(), 1e-14);
  const auto cams = ParseKalibrCamchain(FormatKalibrCamchain({c0, c1}), "camchain.yaml");
  ASSERT_EQ(cams.size(), 2u);
  const UnifiedModel<double> back = UnifiedFromKalibr(cams[0], "cam0");
  EXPECT_EQ(back.xi, u.xi);
  EXPECT_EQ(back.fy, u.fy);
  EXPECT_EQ(back.distortion.p2, u.distortion.p2);
  ASSERT_TRUE(cams[1].T_cn_cnm1.has_value());
  EXPECT_EQ((*cams[1].T_cn_cnm1 - *c1.T_cn_cnm1).norm(), 0.0);
  const UnifiedModel<double> mei = ParseMeiYaml(FormatMeiYaml(u, "cam"), "mei.yaml");
  EXPECT_EQ(mei.xi, u.xi);
  EXPECT_EQ(mei.cx, u.cx);
  EXPECT_EQ(mei.distortion.k1, u.distortion.k1);
  EXPECT_TRUE(LooksLikeMeiYaml(FormatMeiYaml(u, "cam")));
  EXPECT_TRUE(LooksLikeKalibrCamchain(FormatKalibrCamchain({c0})));
}

TEST(CameraFormats, BadFilesAreRefusedNamingTheKey) {
  const auto refused = [](const std::string& text, const std::string& needle) {
    try {
      ParseKalibrCamchain(text, "c.yaml");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const Error& e) { EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what(); }
  };
  refused("cam0: {camera_model: omni, intrinsics: [1, 2, 3], resolution: [640, 480]}", "intrinsics");
  refused("cam0: {camera_model: fisheye62, intrinsics: [1, 2, 3, 4], resolution: [640, 480]}", "unknown camera model");
  refused(
      "cam0: {camera_model: omni, intrinsics: [1, 200, 200, 320, 240], distortion_model: fov, "
      "distortion_coeffs: [0.1], resolution: [640, 480]}",
      "unknown distortion model");
  refused("cam0: {camera_model: omni, intrinsics: [1, 200, 200, 320, 240], resolution: [640.5, 480]}", "resolution");
  refused("cam1: {camera_model: omni}", "no cam0");
  KalibrCamera ds;
  ds.camera_model = "ds", ds.distortion_model = "none", ds.intrinsics = {0, 0.6, 200, 200, 320, 240};
  ds.width = 640, ds.height = 480;
  EXPECT_THROW(UnifiedFromKalibr(ds, "cam0"), Error);
  EXPECT_THROW(ParseMeiYaml("%YAML:1.0\nmodel_type: MEI\nimage_width: 640\nimage_height: 480\n", "m.yaml"), Error);
  EXPECT_THROW(ParseMeiYaml("model_type: KANNALA_BRANDT\n", "m.yaml"), Error);
}

}  // namespace
}  // namespace hovs::calib
