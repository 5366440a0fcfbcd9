// Camera files of other tools, read and written:
//   - Kalibr's camchain YAML (cam0, cam1, ...: camera_model, intrinsics, distortion_model, distortion_coeffs,
//     resolution, T_cn_cnm1): omni + radtan is hovs' unified model (xi, fu, fv, pu, pv; k1, k2, r1, r2); ds,
//     eucm and pinhole + equidistant (Kannala-Brandt) carry the refits of calib/model_refit.h;
//   - CamOdoCal / VINS-Fusion's MEI YAML (model_type: MEI; mirror_parameters xi, distortion_parameters k1 k2 p1
//     p2, projection_parameters gamma1 gamma2 u0 v0), the same unified model.
// Frames: these tools' camera frame is (x, y, -z) of hovs' mirror frame, as OpenCV omnidir's (core/unified.h):
// the intrinsics are the same numbers; a relative pose T converts as S T S, S = diag(1, 1, -1).
#pragma once

#include <Eigen/Dense>
#include <optional>
#include <string>
#include <vector>

#include "calib/model_refit.h"
#include "core/rigid.h"
#include "core/unified.h"

namespace hovs::calib {

struct KalibrCamera {
  std::string camera_model = "omni";  // omni | ds | eucm | pinhole
  std::vector<double> intrinsics;
  std::string distortion_model = "radtan";  // radtan | equidistant | none
  std::vector<double> distortion;
  int width = 0, height = 0;
  std::string rostopic;
  std::optional<Eigen::Matrix4d> T_cn_cnm1;  // this camera from the previous one (tools' frames)
};

KalibrCamera KalibrFromUnified(const UnifiedModel<double>& model);
// A refit (ds, eucm, kb or omni) as a Kalibr camera.
KalibrCamera KalibrFromRefit(const Refit& refit, int width, int height);
// The tools' T_cn_cnm1 of a hovs relative pose between mirror frames (right_from_left); gamma_left and
// gamma_right: the turns about the axis of refitted frames (Refit::axis_rotation_deg, radians here).
Eigen::Matrix4d ToolsFromMirrorPose(const Rigid3d& right_from_left, double gamma_left = 0, double gamma_right = 0);

std::string FormatKalibrCamchain(const std::vector<KalibrCamera>& cameras);

// Basalt's calibration file (its cereal JSON, as in Basalt's own data/euroc_ds_calib.json) for cameras that are
// refits Basalt models: ds (double sphere), eucm, or pinhole + equidistant (Basalt's kb4). There is no IMU: the
// body frame is cam0's (T_imu_cam of cam0 is the identity, of cam i the pose chained from T_cn_cnm1), biases,
// noise and time offsets are zero and the IMU rate is 200 Hz, values Basalt reads but that mean nothing here.
// Throws naming the camera when its model is not one of those.
std::string FormatBasaltCalibration(const std::vector<KalibrCamera>& cameras);
// Throws hovs::Error naming the file and key: not a camchain, missing or malformed keys.
std::vector<KalibrCamera> ParseKalibrCamchain(const std::string& text, const std::string& source);
// The camera as hovs' unified model; throws unless it is omni with radtan (or no) distortion.
UnifiedModel<double> UnifiedFromKalibr(const KalibrCamera& camera, const std::string& where);
bool LooksLikeKalibrCamchain(const std::string& text);

// A MEI file's camera_name is written as a plain YAML scalar: 1 to 64 letters, digits, '_', '-' or '.' (a newline,
// ': ', '#' or a quote would change the file's structure). Throws hovs::Error(where) otherwise.
void CheckMeiCameraName(const std::string& name, const std::string& where);
std::string FormatMeiYaml(const UnifiedModel<double>& model, const std::string& camera_name);
UnifiedModel<double> ParseMeiYaml(const std::string& text, const std::string& source);
bool LooksLikeMeiYaml(const std::string& text);

}  // namespace hovs::calib
