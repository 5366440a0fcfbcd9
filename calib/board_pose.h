// The pose of a board in a camera model's mirror frame from its corners, the model held fixed: PnP (SQPnP) on the
// bearings' normalised coordinates in a virtual pinhole looking along their mean, then refined through the model
// with pixel residuals (Huber, 1 px). Used for held-out images (cross-validation) and by the stereo calibration.
#pragma once

#include <vector>

#include "core/any_model.h"
#include "core/rigid.h"

namespace hovs::calib {

// board_points[i] (board frame, metres) seen at pixels[i]. False when fewer than 4 corners have a bearing or the
// solve fails; *rms_px (optional) is the reprojection RMS over the corners the model projects.
bool FitBoardPose(const AnyModel& model, const std::vector<Vec3d>& board_points, const std::vector<Vec2d>& pixels,
                  Rigid3d* mirror_from_board, double* rms_px = nullptr);

// Reprojection RMS of the corners through the model at this pose (HUGE_VAL when none projects).
double BoardReprojectionRms(const AnyModel& model, const Rigid3d& mirror_from_board,
                            const std::vector<Vec3d>& board_points, const std::vector<Vec2d>& pixels);

}  // namespace hovs::calib
