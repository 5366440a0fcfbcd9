#include "rig/label_pose.h"

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>

#include <cmath>

#include "calib/aruco_dictionary.h"
#include "core/error.h"
#include "core/statistics.h"
#include "depth/marker_edges.h"

namespace hovs::rig {

void LabelOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(min_markers >= 1 && min_markers <= 16, where, "min_markers must be 1..16");
  HOVS_REQUIRE(std::isfinite(max_rms_px) && max_rms_px > 0, where, "max_rms_px must be positive");
}

LabelMeasurement MeasureLabel(const TurretImage& image, const TurretSpec& spec, int k, const LabelOptions& options) {
  options.Check("label options");
  const PinholeCamera<double> cam = spec.ImageCamera();
  HOVS_REQUIRE(image.width == cam.width && image.height == cam.height, "label", "image is ", image.width, "x",
               image.height, " but the camera is ", cam.width, "x", cam.height);
  const cv::Mat grey(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.grey.data()));
  const cv::Ptr<cv::aruco::Dictionary> dict = cv::aruco::getPredefinedDictionary(
      calib::ArucoDictionaryId(spec.label.dictionary, spec.source + " (label.dictionary)"));
  std::vector<std::vector<cv::Point2f>> found;
  std::vector<int> ids;
  cv::aruco::detectMarkers(grey, dict, found, ids);

  const HyperboloidMirror<double>& m = spec.mirrors.at(k).mirror;
  const Vec3d plate_centre(0, 0, m.RimZ());
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> pixels;
  LabelMeasurement out;
  depth::MarkerEdgeOptions edge;
  edge.cells = dict->markerSize + 2;
  for (size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] < 0 || ids[i] >= static_cast<int>(spec.label.centres.size())) continue;
    if (std::find(out.ids.begin(), out.ids.end(), ids[i]) != out.ids.end()) continue;  // a duplicate id
    std::array<Vec2d, 4> c;
    for (int j = 0; j < 4; ++j) c[j] = Vec2d(found[i][j].x, found[i][j].y);
    depth::RefineMarkerCornersByEdges(grey, &c, edge);
    for (int j = 0; j < 4; ++j) {
      const Vec3d p = plate_centre + spec.label.Corner(ids[i], j);
      object.emplace_back(p.x(), p.y(), p.z());
      pixels.emplace_back(c[j].x(), c[j].y());
    }
    out.ids.push_back(ids[i]);
  }
  out.markers = static_cast<int>(out.ids.size());
  HOVS_REQUIRE(out.markers >= options.min_markers, "label", "found ", out.markers, " of ", spec.label.centres.size(),
               " label markers (at least ", options.min_markers, " needed): the label is covered or out of view");
  const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  cv::Mat rvec, tvec;
  const bool ok = cv::solvePnP(object, pixels, K, cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_SQPNP);
  HOVS_REQUIRE(ok, "label", "no pose fits the ", out.markers, " markers");
  cv::solvePnPRefineLM(object, pixels, K, cv::noArray(), rvec, tvec);
  std::vector<cv::Point2d> back;
  cv::projectPoints(object, rvec, tvec, K, cv::noArray(), back);
  double ss = 0;
  for (size_t i = 0; i < back.size(); ++i) ss += std::pow(cv::norm(back[i] - pixels[i]), 2);
  out.rms_px = std::sqrt(ss / back.size());
  HOVS_REQUIRE(out.rms_px <= options.max_rms_px, "label", "the markers' corners fit the plate's pose at ", out.rms_px,
               " px RMS (at most ", options.max_rms_px, "): a marker is misread or the label is bent");
  const auto pose_of = [&](const Eigen::Matrix<double, 6, 1>& p) {
    return PoseFromCamFromMirror(spec, k, Rigid3d(QuaternionFromAngleAxis<double>(Vec3d(p.head<3>())), p.tail<3>()));
  };
  Eigen::Matrix<double, 6, 1> p;
  p << rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2), tvec.at<double>(0), tvec.at<double>(1),
      tvec.at<double>(2);
  out.pose = pose_of(p);
  // The fit's covariance in (rvec, tvec), from OpenCV's Jacobian of the projection, then in the pose's terms by
  // central differences of pose_of.
  cv::Mat jacobian;
  cv::projectPoints(object, rvec, tvec, K, cv::noArray(), back, jacobian);
  Eigen::Matrix<double, 6, 6> JtJ = Eigen::Matrix<double, 6, 6>::Zero();
  for (int r = 0; r < jacobian.rows; ++r) {
    Eigen::Matrix<double, 6, 1> row;
    for (int c = 0; c < 6; ++c) row(c) = jacobian.at<double>(r, c);
    JtJ += row * row.transpose();
  }
  const int dof = 2 * static_cast<int>(object.size()) - 6;
  if (dof > 0 && JtJ.determinant() > 0) {
    const Eigen::Matrix<double, 6, 6> cov = (ss / dof) * JtJ.inverse();
    Eigen::Matrix<double, 5, 6> D;
    for (int c = 0; c < 6; ++c) {
      const double h = c < 3 ? 1e-6 : 1e-7;
      Eigen::Matrix<double, 6, 1> a = p, b = p;
      a(c) += h, b(c) -= h;
      const MirrorPose pa = pose_of(a), pb = pose_of(b);
      const Eigen::Matrix<double, 5, 1> da(pa.offset.x(), pa.offset.y(), pa.offset.z(), pa.rotation.x(),
                                           pa.rotation.y());
      const Eigen::Matrix<double, 5, 1> db(pb.offset.x(), pb.offset.y(), pb.offset.z(), pb.rotation.x(),
                                           pb.rotation.y());
      D.col(c) = (da - db) / (2 * h);
    }
    const Eigen::Matrix<double, 5, 5> dev = D * cov * D.transpose();
    for (int j = 0; j < 5; ++j) out.sigma[j] = std::sqrt(std::max(0.0, dev(j, j)));
  }
  return out;
}

std::array<double, 5> LabelPrecision(const TurretSpec& spec, int k, const LabelOptions& options, int images) {
  const MirrorPose nominal;
  std::array<std::vector<double>, 5> sigmas;
  for (int i = 0; i < images; ++i) {
    const LabelMeasurement m =
        MeasureLabel(RenderTurret(spec, k, nominal, spec.mirrors.at(k).PlateHeight(), spec.seed + 104729u * (i + 1)),
                     spec, k, options);
    for (int j = 0; j < 5; ++j) sigmas[j].push_back(m.sigma[j]);
  }
  std::array<double, 5> out{};
  for (int j = 0; j < 5; ++j) out[j] = Median(sigmas[j]);
  return out;
}

}  // namespace hovs::rig
