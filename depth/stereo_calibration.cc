#include "depth/stereo_calibration.h"

#include "calib/board_pose.h"

#include <ceres/ceres.h>

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <cmath>
#include <memory>
#include <algorithm>
#include <set>

#include "calib/aruco_dictionary.h"
#include "depth/marker_edges.h"
#include "core/error.h"

namespace hovs::depth {
namespace {

constexpr double kDeg = M_PI / 180;

// Pose parameters: Eigen quaternion storage (x, y, z, w) and a translation.
struct PoseParams {
  double q[4], t[3];
  static PoseParams From(const Rigid3d& p) {
    PoseParams r;
    const Eigen::Quaterniond q = p.rotation.normalized();
    r.q[0] = q.x(), r.q[1] = q.y(), r.q[2] = q.z(), r.q[3] = q.w();
    for (int i = 0; i < 3; ++i) r.t[i] = p.translation(i);
    return r;
  }
};
Rigid3d ToPose(const double* q, const double* t) {
  return Rigid3d(Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized(), Vec3d(t[0], t[1], t[2]));
}

// Reprojection of a board point through a catadioptric model, for a unit whose board pose is
// unit_from_left * left_from_board (unit_from_left absent for the left unit).
struct LeftCost {
  const AnyModel* model;
  Vec3d X;
  Vec2d obs;
  bool operator()(const double* q, const double* t, double* r) const {
    Vec2d uv;
    if (!model->ImgFromPointUnbounded(ToPose(q, t) * X, &uv)) return false;
    r[0] = uv(0) - obs(0), r[1] = uv(1) - obs(1);
    return true;
  }
};
struct RightCost {
  const AnyModel* model;
  Vec3d X;
  Vec2d obs;
  bool operator()(const double* qrl, const double* trl, const double* q, const double* t, double* r) const {
    Vec2d uv;
    if (!model->ImgFromPointUnbounded(ToPose(qrl, trl) * (ToPose(q, t) * X), &uv)) return false;
    r[0] = uv(0) - obs(0), r[1] = uv(1) - obs(1);
    return true;
  }
};

double Rms(const AnyModel& model, const Rigid3d& mirror_from_board, const std::vector<CornerObservation>& c,
           const std::map<int, Vec3d>& board) {
  double s = 0;
  int n = 0;
  for (const auto& o : c) {
    const auto it = board.find(o.id);
    if (it == board.end()) continue;
    Vec2d uv;
    if (!model.ImgFromPointUnbounded(mirror_from_board * it->second, &uv)) continue;
    s += (uv - o.pixel).squaredNorm();
    ++n;
  }
  return n ? std::sqrt(s / n) : HUGE_VAL;
}

}  // namespace

void MarkerDetectOptions::Check(const std::string& where) const {
  calib::ArucoDictionaryId(dictionary, where + " (dictionary)");
  HOVS_REQUIRE(views >= 1 && views <= 64, where, "views must be 1..64");
  HOVS_REQUIRE(hfov_deg > 0 && hfov_deg < 170 && width >= 64 && height >= 64, where, "bad view size or field");
  HOVS_REQUIRE(corner_refinement == "edges" || corner_refinement == "subpix", where + ".corner_refinement",
               "unknown corner refinement '", corner_refinement, "' (known: edges, subpix)");
}

void StereoCalibrationOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(std::isfinite(huber_px) && huber_px > 0, where + ".huber_px", "must be positive (got ", huber_px, ")");
  HOVS_REQUIRE(min_common_markers >= 1, where + ".min_common_markers", "must be >= 1 (got ", min_common_markers, ")");
  HOVS_REQUIRE(max_iterations >= 1, where + ".max_iterations", "must be >= 1 (got ", max_iterations, ")");
  HOVS_REQUIRE(residual == "reprojection" || residual == "3d", where + ".residual", "unknown residual '", residual,
               "' (known: reprojection, 3d)");
}

namespace {
// The article's residual: a corner in the right unit's frame predicted from the left unit's frame.
struct Residual3d {
  Vec3d pl, pr;
  template <class T>
  bool operator()(const T* q, const T* t, T* r) const {
    const Eigen::Quaternion<T> Q(q[3], q[0], q[1], q[2]);
    const Vec3<T> x = Q * pl.cast<T>() + Vec3<T>(t[0], t[1], t[2]) - pr.cast<T>();
    for (int i = 0; i < 3; ++i) r[i] = x(i);
    return true;
  }
};
}  // namespace

MarkerDetector::MarkerDetector(const AnyModel& model, const MarkerDetectOptions& o) : model_(model), options_(o) {
  o.Check("marker detection");
  unwrap::Layout layout;
  layout.name = "aruco-ring";
  for (int i = 0; i < o.views; ++i) {
    unwrap::ViewSpec v;
    v.name = "ring" + std::to_string(i);
    v.width = o.width, v.height = o.height;
    v.yaw_deg = 360.0 * i / o.views, v.pitch_deg = o.pitch_deg, v.hfov_deg = o.hfov_deg;
    layout.views.push_back(v);
  }
  table_ = unwrap::BuildRemapTable(model_, layout, {});
}

std::vector<CornerObservation> MarkerDetector::Detect(const unwrap::Image8& image) const {
  HOVS_REQUIRE(image.width == model_.width() && image.height == model_.height(), "marker detection", "the image is ",
               image.width, " x ", image.height, " but the model is for ", model_.width(), " x ", model_.height());
  unwrap::Remapper remapper(table_);
  std::vector<unwrap::Image8> views;
  remapper.Run(image.View(image.channels == 3 ? unwrap::PixelFormat::kRgb8 : unwrap::PixelFormat::kGray8),
               unwrap::Interpolation::kBicubic, &views);
  const auto dict =
      cv::aruco::getPredefinedDictionary(calib::ArucoDictionaryId(options_.dictionary, "marker detection"));
  auto params = cv::aruco::DetectorParameters::create();
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  params->cornerRefinementWinSize = 4;
  params->cornerRefinementMinAccuracy = 0.01;
  // Best detection per marker: the one nearest its view's centre.
  struct Best {
    double dist = HUGE_VAL;
    std::array<Vec2d, 4> px;
  };
  std::map<int, Best> best;
  for (size_t v = 0; v < views.size(); ++v) {
    cv::Mat m(views[v].height, views[v].width, views[v].channels == 3 ? CV_8UC3 : CV_8UC1, views[v].data.data());
    cv::Mat grey;
    if (views[v].channels == 3)
      cv::cvtColor(m, grey, cv::COLOR_RGB2GRAY);
    else
      grey = m;
    std::vector<std::vector<cv::Point2f>> corners;
    std::vector<int> ids;
    cv::aruco::detectMarkers(grey, dict, corners, ids, params);
    const auto& view = table_.views[v].view;
    for (size_t k = 0; k < ids.size(); ++k) {
      Vec2d c = Vec2d::Zero();
      std::array<Vec2d, 4> src;
      bool ok = true;
      for (int j = 0; j < 4; ++j) {
        const Vec2d p(corners[k][j].x, corners[k][j].y);
        c += 0.25 * p;
        Vec3d b;
        ok = ok && view.MirrorFromImg(p, &b) && model_.ImgFromMirror(b, &src[j]);
      }
      if (!ok) continue;
      const double dist = (c - Vec2d(0.5 * (view.width - 1), 0.5 * (view.height - 1))).norm();
      Best& b = best[ids[k]];
      if (dist < b.dist) b.dist = dist, b.px = src;
    }
  }
  // Sub-pixel refinement in the catadioptric image itself (the views are resampled; the corner is not).
  cv::Mat src(image.height, image.width, image.channels == 3 ? CV_8UC3 : CV_8UC1,
              const_cast<uint8_t*>(image.data.data()));
  cv::Mat grey;
  if (image.channels == 3)
    cv::cvtColor(src, grey, cv::COLOR_RGB2GRAY);
  else
    grey = src;
  std::vector<cv::Point2f> pts;
  std::vector<int> ids;
  for (const auto& [id, b] : best)
    for (int j = 0; j < 4; ++j) {
      pts.emplace_back(float(b.px[j].x()), float(b.px[j].y()));
      ids.push_back(4 * id + j);
    }
  std::vector<cv::Point2f> refined = pts;
  if (!refined.empty())
    cv::cornerSubPix(grey, refined, cv::Size(options_.refine_window, options_.refine_window), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-3));
  // Guides for the edge measurement: the corner window's result unless it wandered off.
  std::vector<Vec2d> guide(pts.size());
  std::vector<char> guide_ok(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    const Vec2d a(pts[i].x, pts[i].y), r(refined[i].x, refined[i].y);
    guide_ok[i] = (a - r).norm() <= options_.max_refine_shift_px;
    guide[i] = guide_ok[i] ? r : a;
  }
  std::vector<char> by_edges(pts.size(), 0);
  if (options_.corner_refinement == "edges") {
    MarkerEdgeOptions eo;
    eo.cells = dict->markerSize + 2;
    for (size_t m = 0; m + 3 < pts.size(); m += 4) {
      // Repeated from its own result until the corners settle (each pass starts from better guides where the
      // unwrapped view's detection was poor, e.g. markers squeezed near the rim; at most 4 passes). A corner
      // is taken when its last move was under 0.1 px; it may then be further than the corner window's limit
      // from the first detection (up to half a cell). A corner whose edges were measured but did not settle
      // is dropped rather than left to cornerSubPix, which the board's edge and the inner bits pull.
      std::array<Vec2d, 4> c{guide[m], guide[m + 1], guide[m + 2], guide[m + 3]};
      std::array<bool, 4> ok{};
      std::array<double, 4> moved{HUGE_VAL, HUGE_VAL, HUGE_VAL, HUGE_VAL};
      for (int pass = 0; pass < 4; ++pass) {
        std::array<Vec2d, 4> next = c;
        ok = RefineMarkerCornersByEdges(grey, &next, eo);
        double worst = 0;
        for (int j = 0; j < 4; ++j) {
          moved[j] = ok[j] ? (next[j] - c[j]).norm() : HUGE_VAL;
          if (ok[j]) worst = std::max(worst, moved[j]);
        }
        c = next;
        if (pass > 0 && worst < 0.02) break;
      }
      double side = 0;
      for (int j = 0; j < 4; ++j) side += 0.25 * (c[j] - c[(j + 1) % 4]).norm();
      const double limit = std::max(options_.max_refine_shift_px, 0.5 * side / eo.cells);
      for (int j = 0; j < 4; ++j) {
        if (!ok[j]) continue;  // not measurable: the corner window's result stands
        if (moved[j] > 0.1 || (c[j] - Vec2d(pts[m + j].x, pts[m + j].y)).norm() > limit) {
          guide_ok[m + j] = 0;  // measured but unstable, or far from the detection: dropped
          continue;
        }
        guide[m + j] = c[j], by_edges[m + j] = 1;
      }
    }
  }
  std::vector<CornerObservation> out;
  for (size_t i = 0; i < pts.size(); ++i) {
    // A refinement that wanders off is not a marker corner (another edge, a partly hidden marker): dropped.
    if (!guide_ok[i] && !by_edges[i]) continue;
    out.push_back({ids[i], guide[i], by_edges[i] != 0});
  }
  return out;
}

bool BoardPose(const AnyModel& model, const std::vector<CornerObservation>& corners, const std::map<int, Vec3d>& board,
               Rigid3d* mirror_from_board, double* rms_px) {
  std::vector<Vec3d> pts;
  std::vector<Vec2d> obs;
  for (const auto& c : corners) {
    const auto it = board.find(c.id);
    if (it != board.end()) pts.push_back(it->second), obs.push_back(c.pixel);
  }
  return calib::FitBoardPose(model, pts, obs, mirror_from_board, rms_px);
}

StereoCalibration CalibrateStereo(const AnyModel& left, const AnyModel& right,
                                  const std::vector<StereoPairObservation>& pairs, const std::map<int, Vec3d>& board,
                                  const StereoCalibrationOptions& o) {
  o.Check("stereo calibration");
  HOVS_REQUIRE(pairs.size() >= 2, "stereo calibration", "needs at least two pairs (got ", pairs.size(), ")");
  struct Pair {
    size_t index;
    Rigid3d left_from_board, right_from_board;
  };
  std::vector<Pair> usable;
  std::string rejected;
  for (size_t i = 0; i < pairs.size(); ++i) {
    std::set<int> ml, mr;
    for (const auto& c : pairs[i].left) ml.insert(c.id / 4);
    for (const auto& c : pairs[i].right) mr.insert(c.id / 4);
    int common = 0;
    for (int m : ml) common += mr.count(m);
    Pair p{i, {}, {}};
    double rl = 0, rr = 0;
    if (common < o.min_common_markers) {
      rejected += " " + pairs[i].name + " (" + std::to_string(common) + " common markers)";
      continue;
    }
    if (!BoardPose(left, pairs[i].left, board, &p.left_from_board, &rl) ||
        !BoardPose(right, pairs[i].right, board, &p.right_from_board, &rr)) {
      rejected += " " + pairs[i].name + " (no board pose)";
      continue;
    }
    usable.push_back(p);
  }
  HOVS_REQUIRE(usable.size() >= 2, "stereo calibration", "fewer than two usable pairs; rejected:", rejected);
  // Initial relative pose: the pair with the most corners.
  size_t best = 0;
  for (size_t k = 1; k < usable.size(); ++k)
    if (pairs[usable[k].index].left.size() + pairs[usable[k].index].right.size() >
        pairs[usable[best].index].left.size() + pairs[usable[best].index].right.size())
      best = k;
  PoseParams rl = PoseParams::From(usable[best].right_from_board * usable[best].left_from_board.Inverse());
  if (o.residual == "3d") {
    ceres::Problem p3;
    int n3 = 0;
    for (const auto& u : usable) {
      std::set<int> in_right;
      for (const auto& c : pairs[u.index].right) in_right.insert(c.id);
      for (const auto& c : pairs[u.index].left) {
        const auto it = board.find(c.id);
        if (it == board.end() || !in_right.count(c.id)) continue;
        p3.AddResidualBlock(new ceres::AutoDiffCostFunction<Residual3d, 3, 4, 3>(
                                new Residual3d{u.left_from_board * it->second, u.right_from_board * it->second}),
                            nullptr, rl.q, rl.t);
        ++n3;
      }
    }
    HOVS_REQUIRE(n3 >= 3, "stereo calibration (3d)", "fewer than 3 corners seen by both units");
    p3.SetManifold(rl.q, new ceres::EigenQuaternionManifold);
    ceres::Solver::Options so;
    so.max_num_iterations = o.max_iterations;
    so.function_tolerance = 1e-14, so.parameter_tolerance = 1e-14, so.gradient_tolerance = 1e-14;
    ceres::Solver::Summary s3;
    ceres::Solve(so, &p3, &s3);
    StereoCalibration out;
    out.residual = "3d";
    out.converged = s3.termination_type == ceres::CONVERGENCE;
    out.solver_report = s3.BriefReport();
    out.right_from_left = ToPose(rl.q, rl.t);
    out.baseline = Vec3d(rl.t[0], rl.t[1], rl.t[2]).norm();
    out.rms_3d_m = std::sqrt(2 * s3.final_cost / n3);
    double s2 = 0;
    int n = 0;
    for (const auto& u : usable) {
      const auto& pr = pairs[u.index];
      out.left_from_board.push_back(u.left_from_board);
      out.pair_names.push_back(pr.name);
      const double el = Rms(left, u.left_from_board, pr.left, board),
                   er = Rms(right, out.right_from_left * u.left_from_board, pr.right, board);
      out.pair_rms_left_px.push_back(el), out.pair_rms_right_px.push_back(er);
      out.pair_corners_left.push_back(static_cast<int>(pr.left.size()));
      out.pair_corners_right.push_back(static_cast<int>(pr.right.size()));
      s2 += el * el * pr.left.size() + er * er * pr.right.size();
      n += static_cast<int>(pr.left.size() + pr.right.size());
    }
    out.rms_px = std::sqrt(s2 / std::max(1, n));
    return out;
  }
  std::vector<PoseParams> lb(usable.size());
  std::vector<StereoPairObservation> obs;
  for (size_t k = 0; k < usable.size(); ++k) {
    lb[k] = PoseParams::From(usable[k].left_from_board);
    obs.push_back(pairs[usable[k].index]);
  }
  std::vector<StereoOutlier> outliers;
  std::unique_ptr<ceres::Problem> problem;
  ceres::Solver::Summary summary;
  // Solve; drop corners whose residual exceeds outlier_px (a marker partly hidden can still decode), solve again.
  for (int pass = 0; pass < 2; ++pass) {
    problem = std::make_unique<ceres::Problem>();
    for (size_t k = 0; k < obs.size(); ++k) {
      for (const auto& c : obs[k].left) {
        const auto it = board.find(c.id);
        if (it == board.end()) continue;
        problem->AddResidualBlock(new ceres::NumericDiffCostFunction<LeftCost, ceres::CENTRAL, 2, 4, 3>(
                                      new LeftCost{&left, it->second, c.pixel}),
                                  new ceres::HuberLoss(o.huber_px), lb[k].q, lb[k].t);
      }
      for (const auto& c : obs[k].right) {
        const auto it = board.find(c.id);
        if (it == board.end()) continue;
        problem->AddResidualBlock(new ceres::NumericDiffCostFunction<RightCost, ceres::CENTRAL, 2, 4, 3, 4, 3>(
                                      new RightCost{&right, it->second, c.pixel}),
                                  new ceres::HuberLoss(o.huber_px), rl.q, rl.t, lb[k].q, lb[k].t);
      }
      problem->SetManifold(lb[k].q, new ceres::EigenQuaternionManifold);
    }
    problem->SetManifold(rl.q, new ceres::EigenQuaternionManifold);
    ceres::Solver::Options so;
    so.max_num_iterations = o.max_iterations;
    so.linear_solver_type = ceres::DENSE_SCHUR;
    so.function_tolerance = 1e-12, so.parameter_tolerance = 1e-12, so.gradient_tolerance = 1e-12;
    ceres::Solve(so, problem.get(), &summary);
    HOVS_REQUIRE(summary.termination_type != ceres::FAILURE, "stereo calibration",
                 "the solver failed: ", summary.message);
    if (pass == 1 || !(o.outlier_px > 0)) break;
    size_t dropped = 0;
    const Rigid3d R = ToPose(rl.q, rl.t);
    for (size_t k = 0; k < obs.size(); ++k) {
      const Rigid3d L = ToPose(lb[k].q, lb[k].t);
      for (int side = 0; side < 2; ++side) {
        auto& cs = side == 0 ? obs[k].left : obs[k].right;
        const AnyModel& model = side == 0 ? left : right;
        const Rigid3d pose = side == 0 ? L : R * L;
        std::vector<CornerObservation> kept;
        for (const auto& c : cs) {
          const auto it = board.find(c.id);
          Vec2d uv;
          const double e = it != board.end() && model.ImgFromPointUnbounded(pose * it->second, &uv)
                               ? (uv - c.pixel).norm()
                               : HUGE_VAL;
          if (e > o.outlier_px) {
            outliers.push_back({obs[k].name, side == 0 ? "left" : "right", c.id, e});
            ++dropped;
          } else {
            kept.push_back(c);
          }
        }
        cs = kept;
      }
    }
    if (dropped == 0) break;
  }

  StereoCalibration out;
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  out.solver_report = summary.BriefReport();
  out.right_from_left = ToPose(rl.q, rl.t);
  const Vec3d t(rl.t[0], rl.t[1], rl.t[2]);
  out.baseline = t.norm();
  double s2 = 0;
  int n = 0;
  for (size_t k = 0; k < usable.size(); ++k) {
    const auto& pr = obs[k];
    const Rigid3d L = ToPose(lb[k].q, lb[k].t);
    out.left_from_board.push_back(L);
    out.pair_names.push_back(pr.name);
    const double el = Rms(left, L, pr.left, board), er = Rms(right, out.right_from_left * L, pr.right, board);
    out.pair_rms_left_px.push_back(el);
    out.pair_rms_right_px.push_back(er);
    out.pair_corners_left.push_back(static_cast<int>(pr.left.size()));
    out.pair_corners_right.push_back(static_cast<int>(pr.right.size()));
    s2 += el * el * pr.left.size() + er * er * pr.right.size();
    n += static_cast<int>(pr.left.size() + pr.right.size());
  }
  out.rms_px = std::sqrt(s2 / std::max(1, n));
  out.outliers = outliers;
  // Covariance of the relative pose, scaled by the residual variance (pixels are not known to 1 px).
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.null_space_rank = -1;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> blocks = {{rl.q, rl.q}, {rl.t, rl.t}};
  if (cov.Compute(blocks, problem.get())) {
    const double dof = std::max(1.0, double(summary.num_residuals - summary.num_effective_parameters));
    const double scale = 2 * summary.final_cost / dof;  // residual variance
    double cq[9], ct[9];
    cov.GetCovarianceMatrixInTangentSpace({rl.q}, cq);
    cov.GetCovarianceBlock(rl.t, rl.t, ct);
    // Ceres' quaternion tangent delta rotates by 2 |delta|.
    for (int i = 0; i < 3; ++i) {
      out.sigma_rotation_deg(i) = 2 * std::sqrt(std::max(0.0, cq[4 * i] * scale)) / kDeg;
      out.sigma_translation(i) = std::sqrt(std::max(0.0, ct[4 * i] * scale));
    }
    const Vec3d u = t / out.baseline;
    double var = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) var += u(i) * ct[3 * i + j] * u(j);
    out.sigma_baseline = std::sqrt(std::max(0.0, var * scale));
  }
  return out;
}

std::vector<int> RejectInconsistentMarkers(const AnyModel& model, std::vector<CornerObservation>* corners,
                                           const std::map<int, Vec3d>& board, double max_px) {
  std::vector<int> removed;
  for (;;) {
    std::set<int> markers;
    for (const auto& c : *corners) markers.insert(c.id / 4);
    if (markers.size() < 3) return removed;
    Rigid3d pose;
    double rms = 0;
    if (!BoardPose(model, *corners, board, &pose, &rms)) return removed;
    std::map<int, double> worst;
    for (const auto& c : *corners) {
      const auto it = board.find(c.id);
      Vec2d uv;
      const double e =
          it != board.end() && model.ImgFromPointUnbounded(pose * it->second, &uv) ? (uv - c.pixel).norm() : HUGE_VAL;
      worst[c.id / 4] = std::max(worst[c.id / 4], e);
    }
    const auto w =
        std::max_element(worst.begin(), worst.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
    if (w->second <= max_px) return removed;
    removed.push_back(w->first);
    corners->erase(std::remove_if(corners->begin(), corners->end(),
                                  [&](const CornerObservation& c) { return c.id / 4 == w->first; }),
                   corners->end());
  }
}

}  // namespace hovs::depth
