#include "calib/omnidir_reference.h"

#include <opencv2/ccalib/omnidir.hpp>
#include <opencv2/core.hpp>

#include <cmath>

namespace hovs::calib {

OmnidirResult RunOpenCvOmnidir(const std::vector<BoardObservation>& obs, int width, int height) {
  OmnidirResult out;
  std::vector<cv::Mat> object_points, image_points;
  for (const auto& o : obs) {
    cv::Mat op(1, static_cast<int>(o.pixels.size()), CV_64FC3), ip(1, static_cast<int>(o.pixels.size()), CV_64FC2);
    for (size_t j = 0; j < o.pixels.size(); ++j) {
      op.at<cv::Vec3d>(0, static_cast<int>(j)) = cv::Vec3d(o.board_points[j].x(), o.board_points[j].y(), 0);
      ip.at<cv::Vec2d>(0, static_cast<int>(j)) = cv::Vec2d(o.pixels[j].x(), o.pixels[j].y());
    }
    object_points.push_back(op);
    image_points.push_back(ip);
  }
  cv::Mat K, xi, D, idx;
  std::vector<cv::Mat> rvecs, tvecs;
  try {
    out.opencv_rms = cv::omnidir::calibrate(
        object_points, image_points, cv::Size(width, height), K, xi, D, rvecs, tvecs, cv::omnidir::CALIB_FIX_SKEW,
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 300, 1e-10), idx);
  } catch (const cv::Exception& e) {
    out.error = e.what();
    return out;
  }
  out.xi = xi.at<double>(0);
  out.fx = K.at<double>(0, 0), out.fy = K.at<double>(1, 1), out.cx = K.at<double>(0, 2), out.cy = K.at<double>(1, 2);
  out.skew = K.at<double>(0, 1);
  out.k1 = D.at<double>(0), out.k2 = D.at<double>(1), out.p1 = D.at<double>(2), out.p2 = D.at<double>(3);
  double sum2 = 0;
  size_t n = 0;
  for (int k = 0; k < static_cast<int>(idx.total()); ++k) {
    const int i = idx.at<int>(k);
    cv::Mat projected;
    cv::omnidir::projectPoints(object_points[i], projected, rvecs[k], tvecs[k], K, out.xi, D);
    for (int j = 0; j < projected.cols; ++j) {
      const cv::Vec2d p = projected.at<cv::Vec2d>(0, j), q = image_points[i].at<cv::Vec2d>(0, j);
      sum2 += (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]);
      ++n;
    }
  }
  out.images_used = static_cast<int>(idx.total());
  out.rms = n ? std::sqrt(sum2 / n) : 0;
  out.ok = n > 0;
  return out;
}

}  // namespace hovs::calib
