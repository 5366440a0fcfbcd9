#include "calib/board_suggestion.h"

#include <algorithm>
#include <cmath>

#include "calib/solver_util.h"
#include "core/error.h"

namespace hovs::calib {
namespace {

constexpr double kDeg = M_PI / 180;

// The solve's information in a normalised space: parameters divided by their standard deviations (so a focal
// length and a fourth-order coefficient are alike), fixed parameters (zero variance) masked out.
struct NormalisedInformation {
  Eigen::VectorXd scale;    // the standard deviation of each parameter (1 where fixed)
  Eigen::VectorXd free;     // 1 for a free parameter, 0 for a fixed one
  Eigen::MatrixXd H;        // pseudo-inverse of the normalised covariance
  int null_dimensions = 0;  // gauge freedoms and fixed parameters
};

NormalisedInformation Normalise(const Eigen::MatrixXd& C) {
  NormalisedInformation n;
  const int D = static_cast<int>(C.rows());
  n.scale = C.diagonal().cwiseMax(0).cwiseSqrt();
  n.free = (n.scale.array() > 0).cast<double>();
  for (int i = 0; i < D; ++i)
    if (!(n.scale(i) > 0)) n.scale(i) = 1;
  const Eigen::MatrixXd Cn = n.scale.cwiseInverse().asDiagonal() * C * n.scale.cwiseInverse().asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Cn);
  const double top = es.eigenvalues().maxCoeff();
  n.H.setZero(D, D);
  for (int k = 0; k < D; ++k) {
    const double l = es.eigenvalues()(k);
    if (l > 1e-9 * top)
      n.H += es.eigenvectors().col(k) * es.eigenvectors().col(k).transpose() / l;
    else
      ++n.null_dimensions;
  }
  return n;
}

// The pseudo-inverse of a symmetric information matrix, its `null` smallest eigenvalues dropped.
Eigen::MatrixXd PseudoInverse(const Eigen::MatrixXd& H, int null) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(H.rows(), H.cols());
  for (int k = null; k < H.rows(); ++k)
    if (es.eigenvalues()(k) > 0)
      C += es.eigenvectors().col(k) * es.eigenvectors().col(k).transpose() / es.eigenvalues()(k);
  return C;
}

// One evaluation point of the field: its gradient over the solve's parameters (normalised) and the data to add a
// board's pose column.
struct FieldPoint {
  Eigen::MatrixXd G;  // 2 x D, normalised
  Eigen::Matrix<double, 2, 3> d_point;
  Vec3d p;
};

struct Candidate {
  BoardSuggestion board;
  Eigen::MatrixXd A;  // 2m x (D + 6): the corners' Jacobian, normalised (new pose last, unscaled)
};

double WorstSigma(const Eigen::Matrix2d& c) {
  const double t = 0.5 * (c(0, 0) + c(1, 1)), d = c.determinant();
  return std::sqrt(std::max(0.0, t + std::sqrt(std::max(0.0, t * t - d))));
}

// The mean 1-sigma over the field when the boards of `added` (each with its pose columns) join the solve.
double FieldMean(const std::vector<FieldPoint>& field, const NormalisedInformation& info, double sigma, int n_poses,
                 int K, const std::vector<const Candidate*>& added, bool infinite) {
  const int D = static_cast<int>(info.H.rows()), E = D + 6 * static_cast<int>(added.size());
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(E, E);
  H.topLeftCorner(D, D) = info.H;
  for (size_t a = 0; a < added.size(); ++a) {
    const Eigen::MatrixXd& A = added[a]->A;
    const int col = D + 6 * static_cast<int>(a);
    // The corners inform the intrinsics (first K) and their own pose.
    Eigen::MatrixXd B = Eigen::MatrixXd::Zero(A.rows(), E);
    B.leftCols(K) = A.leftCols(K);
    B.middleCols(col, 6) = A.rightCols(6);
    H += B.transpose() * B / (sigma * sigma);
  }
  const Eigen::MatrixXd C = PseudoInverse(H, info.null_dimensions);
  const int n_total = n_poses + static_cast<int>(added.size());
  double sum = 0;
  for (const auto& f : field) {
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(2, E);
    G.leftCols(K) = f.G.leftCols(K);
    G.middleCols(K, D - K) = f.G.rightCols(D - K) * (static_cast<double>(n_poses) / n_total);
    for (size_t a = 0; a < added.size(); ++a) {
      const Rigid3d& T = added[a]->board.cam_from_board;
      const std::array<double, 6> params = PoseToParams(T);
      const Vec3d b = infinite ? Vec3d(T.rotation.conjugate() * f.p) : Vec3d(T.Inverse() * f.p);
      const int col = D + 6 * static_cast<int>(a);
      G.middleCols(col, 3) = f.d_point * RotatedPointJacobian(params.data(), b) / n_total;
      if (!infinite) G.middleCols(col + 3, 3) = f.d_point / n_total;
    }
    sum += WorstSigma(G * C * G.transpose());
  }
  return sum / field.size();
}

std::vector<FieldPoint> Field(const ParametricModel& model, const SolveCovariance& solve, const UncertaintyOptions& m,
                              const Eigen::VectorXd& scale) {
  const ImageGrid grid = ImageGrid::Over(model.width(), model.height(), std::max(1, model.width() / 24));
  std::vector<FieldPoint> field;
  for (int j = 0; j < grid.ny; ++j)
    for (int i = 0; i < grid.nx; ++i) {
      const Vec2d uv(i * grid.step_px, j * grid.step_px);
      const double r = (uv - m.centre).norm();
      if (m.rho_max > 0 && (r < m.rho_min || r > m.rho_max)) continue;
      Vec3d v;
      if (!model.CamFromImg(uv, &v)) continue;
      FieldPoint f;
      f.p = m.range_m > 0 ? Vec3d(m.range_m * v.normalized()) : v.normalized();
      if (!ProjectionGradient(model, solve.cam_from_board, f.p, m.range_m == 0, &f.G, &f.d_point)) continue;
      f.G = f.G * scale.asDiagonal();
      field.push_back(std::move(f));
    }
  return field;
}

// The board seen whole at this pose, with its corners' normalised Jacobian.
bool MakeCandidate(const ParametricModel& model, const std::vector<Vec3d>& points, const Rigid3d& cam_from_board,
                   const UncertaintyOptions& m, const NormalisedInformation& info, Candidate* c) {
  const int K = model.size();
  const std::array<double, 6> params = PoseToParams(cam_from_board);
  c->A.setZero(2 * points.size(), K + 6);
  c->board.corners_px.clear();
  for (size_t j = 0; j < points.size(); ++j) {
    Vec2d uv;
    Eigen::MatrixXd d_intr;
    Eigen::Matrix<double, 2, 3> d_point;
    if (!model.ImgFromCamJacobians(cam_from_board * points[j], &uv, &d_intr, &d_point)) return false;
    if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() <= model.width() - 1 && uv.y() <= model.height() - 1)) return false;
    const double r = (uv - m.centre).norm();
    if (m.rho_max > 0 && (r < m.rho_min || r > m.rho_max)) return false;
    c->board.corners_px.push_back(uv);
    for (int k = 0; k < K; ++k) d_intr.col(k) *= info.scale(k) * info.free(k);
    c->A.block(2 * j, 0, 2, K) = d_intr;
    c->A.block(2 * j, K, 2, 3) = d_point * RotatedPointJacobian(params.data(), points[j]);
    c->A.block(2 * j, K + 3, 2, 3) = d_point;
  }
  return true;
}

}  // namespace

void SuggestOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(count >= 1 && count <= 20, where, "suggest 1 to 20 boards (got ", count, ")");
  for (double d : distances_m) HOVS_REQUIRE(d > 0 && std::isfinite(d), where, "distances must be positive");
}

Suggestions SuggestBoardPoses(const ParametricModel& model, const SolveCovariance& solve,
                              const std::vector<Vec3d>& board_points, const UncertaintyOptions& map,
                              const SuggestOptions& o) {
  o.Check("board suggestion");
  map.Check("board suggestion");
  HOVS_REQUIRE(solve.valid(), "board suggestion", "the solve's covariance is not available");
  HOVS_REQUIRE(board_points.size() >= 4, "board suggestion", "the board has fewer than 4 corners");
  const int K = model.size(), n = static_cast<int>(solve.cam_from_board.size());
  const NormalisedInformation info = Normalise(solve.covariance);
  const std::vector<FieldPoint> field = Field(model, solve, map, info.scale);
  HOVS_REQUIRE(!field.empty(), "board suggestion", "no pixel of the calibrated field has a ray");
  // The board centred on its centroid; the suggested pose is reported for the caller's board frame.
  Vec3d centroid = Vec3d::Zero();
  for (const auto& p : board_points) centroid += p / board_points.size();
  std::vector<double> distances = o.distances_m;
  if (distances.empty()) {
    std::vector<double> d;
    for (const auto& T : solve.cam_from_board) d.push_back((T * centroid).norm());
    std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
    for (double f : {0.75, 1.0, 1.33}) distances.push_back(f * d[d.size() / 2]);
  }
  // The field's elevation range: the rays at the annulus' inner and outer radius.
  double el_lo = -80 * kDeg, el_hi = 10 * kDeg;
  if (map.rho_max > 0) {
    Vec3d a, b;
    if (model.CamFromImg(map.centre + Vec2d(map.rho_min, 0), &a) &&
        model.CamFromImg(map.centre + Vec2d(map.rho_max, 0), &b)) {
      el_lo = std::min(std::atan2(a.z(), a.head<2>().norm()), std::atan2(b.z(), b.head<2>().norm()));
      el_hi = std::max(std::atan2(a.z(), a.head<2>().norm()), std::atan2(b.z(), b.head<2>().norm()));
    }
  }
  std::vector<Candidate> candidates;
  for (int ia = 0; ia < 12; ++ia)
    for (double fe : {0.1, 0.3, 0.5, 0.7, 0.9})
      for (double dist : distances)
        for (double tilt : {-35.0, 0.0, 35.0}) {
          const double az = ia * 30 * kDeg, el = el_lo + fe * (el_hi - el_lo);
          const Vec3d c = dist * Vec3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
          // Facing the viewpoint, x horizontal, then tilted about x.
          const Vec3d z = -c.normalized(), x = Vec3d(0, 0, 1).cross(z).normalized(), y = z.cross(x);
          Mat3<double> R;
          R.col(0) = x, R.col(1) = y, R.col(2) = z;
          const Eigen::Quaterniond q =
              Eigen::Quaterniond(R) * Eigen::Quaterniond(Eigen::AngleAxisd(tilt * kDeg, Vec3d::UnitX()));
          const Rigid3d pose(q, c - q * centroid);
          Candidate cand;
          if (!MakeCandidate(model, board_points, pose, map, info, &cand)) continue;
          cand.board.cam_from_board = pose;
          cand.board.azimuth_deg = az / kDeg, cand.board.elevation_deg = el / kDeg;
          cand.board.distance_m = dist, cand.board.tilt_deg = tilt;
          model.ImgFromCam(c, &cand.board.centre_px);
          candidates.push_back(std::move(cand));
        }
  HOVS_REQUIRE(!candidates.empty(), "board suggestion",
               "no candidate pose shows the whole board inside the calibrated field");
  Suggestions out;
  out.board_points = board_points;
  out.candidates = static_cast<int>(candidates.size());
  const bool infinite = map.range_m == 0;
  out.mean_px_now = FieldMean(field, info, solve.sigma_px, n, K, {}, infinite);
  std::vector<const Candidate*> chosen;
  std::vector<bool> used(candidates.size(), false);
  for (int round = 0; round < o.count && round < out.candidates; ++round) {
    double best = HUGE_VAL;
    size_t best_k = 0;
    for (size_t k = 0; k < candidates.size(); ++k) {
      if (used[k]) continue;
      std::vector<const Candidate*> trial = chosen;
      trial.push_back(&candidates[k]);
      const double v = FieldMean(field, info, solve.sigma_px, n, K, trial, infinite);
      if (v < best) best = v, best_k = k;
    }
    used[best_k] = true;
    chosen.push_back(&candidates[best_k]);
    BoardSuggestion b = candidates[best_k].board;
    b.mean_px = best;
    out.boards.push_back(std::move(b));
  }
  return out;
}

nlohmann::json SuggestionsJson(const Suggestions& s) {
  nlohmann::json boards = nlohmann::json::array();
  for (const auto& b : s.boards) {
    const Eigen::Quaterniond& q = b.cam_from_board.rotation;
    const Vec3d& t = b.cam_from_board.translation;
    boards.push_back(
        {{"azimuth_deg", b.azimuth_deg},
         {"elevation_deg", b.elevation_deg},
         {"distance_m", b.distance_m},
         {"tilt_deg", b.tilt_deg},
         {"centre_px", {b.centre_px.x(), b.centre_px.y()}},
         {"cam_from_board", {{"qw", q.w()}, {"qx", q.x()}, {"qy", q.y()}, {"qz", q.z()}, {"t", {t.x(), t.y(), t.z()}}}},
         {"mean_px_after", b.mean_px}});
  }
  return {
      {"method", "greedy: each board the candidate that lowers the field's mean 1-sigma projection uncertainty most"},
      {"candidates", s.candidates},
      {"mean_px_now", s.mean_px_now},
      {"boards", boards}};
}

}  // namespace hovs::calib
