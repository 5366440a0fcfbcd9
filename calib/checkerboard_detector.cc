#include "calib/checkerboard_detector.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <opencv2/imgproc.hpp>

#include "calib/checkerboard_edges.h"
#include "core/error.h"
#include "core/format.h"

namespace hovs::calib {

void CheckerboardSpec::Check(const std::string& where) const {
  HOVS_REQUIRE(cols >= 2 && rows >= 2 && cols <= 1000 && rows <= 1000, where,
               "a board has 2 x 2 to 1000 x 1000 inner corners (got ", cols, " x ", rows, ")");
  HOVS_REQUIRE(std::isfinite(square) && square > 0 && square <= 10, where, "square size must be in (0, 10] m (got ",
               square, ")");
}

void CheckerboardDetectOptions::Check(const std::string& where) const {
  if (charuco)
    charuco->Check(where);
  else
    board.Check(where);
  HOVS_REQUIRE(min_corners >= 4, where, "min_corners must be at least 4 (got ", min_corners, ")");
  HOVS_REQUIRE(orientation == 1 || orientation == -1, where, "orientation must be +1 or -1 (got ", orientation, ")");
  HOVS_REQUIRE(std::isfinite(min_contrast) && min_contrast > 0 && min_contrast < 1, where,
               "min_contrast must lie in (0, 1) (got ", min_contrast, ")");
  HOVS_REQUIRE(max_seeds >= 1, where, "max_seeds must be at least 1");
  HOVS_REQUIRE(subpix_half_window >= 0 && subpix_half_window <= 30, where, "subpix_half_window must lie in [0, 30]");
  HOVS_REQUIRE(corner_refinement == "edges" || corner_refinement == "subpix", where,
               "corner_refinement must be 'edges' or 'subpix' (got '", corner_refinement, "')");
  HOVS_REQUIRE(max_label_error > 0 && max_label_error <= 1, where, "max_label_error must lie in (0, 1]");
}

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Candidate {
  Vec2d p;
  double response = 0;
  Vec2d e1, e2;  // unit edge directions (sign arbitrary)
};

double Sample(const cv::Mat& f, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= f.cols || y0 + 1 >= f.rows) return std::nan("");
  const double ax = x - x0, ay = y - y0;
  const float* r0 = f.ptr<float>(y0);
  const float* r1 = f.ptr<float>(y0 + 1);
  return (1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x0 + 1]) + ay * ((1 - ax) * r1[x0] + ax * r1[x0 + 1]);
}

// The circle test: four transitions, contrast, two straight edge lines through the centre.
bool VerifyCorner(const cv::Mat& f, const Vec2d& p, double radius, double min_contrast, Vec2d* e1, Vec2d* e2) {
  constexpr int kN = 48;
  double s[kN];
  double mean = 0;
  for (int k = 0; k < kN; ++k) {
    const double a = 2 * kPi * k / kN;
    s[k] = Sample(f, p.x() + radius * std::cos(a), p.y() + radius * std::sin(a));
    if (!std::isfinite(s[k])) return false;
    mean += s[k];
  }
  mean /= kN;
  double bright = 0, dark = 0;
  int nb = 0, nd = 0;
  for (double v : s) (v > mean ? (bright += v, ++nb) : (dark += v, ++nd));
  if (nb < kN / 6 || nd < kN / 6) return false;
  if (bright / nb - dark / nd < min_contrast) return false;
  double t[4];
  int nt = 0;
  for (int k = 0; k < kN; ++k) {
    const double a = s[k] - mean, b = s[(k + 1) % kN] - mean;
    if ((a > 0) == (b > 0)) continue;
    if (nt == 4) return false;
    const double frac = a / (a - b);
    t[nt++] = 2 * kPi * (k + frac) / kN;
  }
  if (nt != 4) return false;
  auto opposite = [](double x, double y) { return std::abs(std::remainder(y - x - kPi, 2 * kPi)) < 0.4; };
  if (!opposite(t[0], t[2]) || !opposite(t[1], t[3])) return false;
  auto line = [](double a, double b) {
    Vec2d v = Vec2d(std::cos(a), std::sin(a)) - Vec2d(std::cos(b), std::sin(b));
    return Vec2d(v / v.norm());
  };
  *e1 = line(t[0], t[2]);
  *e2 = line(t[1], t[3]);
  // The two lines must really cross (not two nearly parallel edges of a thin stripe).
  return std::abs(e1->x() * e2->y() - e1->y() * e2->x()) > std::sin(15 * kPi / 180);
}

double LineAngle(const Vec2d& a, const Vec2d& b) {  // angle between two lines, in [0, pi/2]
  const double c = std::abs(a.dot(b)) / (a.norm() * b.norm());
  return std::acos(std::min(1.0, c));
}

bool HasEdgeAlong(const Candidate& c, const Vec2d& dir, double tol) {
  return LineAngle(c.e1, dir) < tol || LineAngle(c.e2, dir) < tol;
}

class GridGrower {
 public:
  GridGrower(const std::vector<Candidate>& c, int max_long, int max_short)
      : c_(c), max_long_(max_long), max_short_(max_short) {}

  // Nearest candidate from p along direction d (unit), sharing that edge.
  int Neighbour(int from, const Vec2d& d) const {
    const double tol = 18 * kPi / 180;
    int best = -1;
    double best_dist = 1e30;
    for (size_t q = 0; q < c_.size(); ++q) {
      if (static_cast<int>(q) == from) continue;
      const Vec2d v = c_[q].p - c_[from].p;
      const double dist = v.norm();
      if (dist < 3 || dist >= best_dist) continue;
      if (v.dot(d) / dist < std::cos(tol)) continue;
      if (!HasEdgeAlong(c_[q], v, tol)) continue;
      best = static_cast<int>(q), best_dist = dist;
    }
    return best;
  }

  int Nearest(const Vec2d& pred, double radius, const std::vector<char>& used) const {
    int best = -1;
    double best_d = radius;
    for (size_t q = 0; q < c_.size(); ++q) {
      if (used[q]) continue;
      const double d = (c_[q].p - pred).norm();
      if (d < best_d) best = static_cast<int>(q), best_d = d;
    }
    return best;
  }

  // A 3 x 3 grid around the seed, or empty.
  std::vector<std::vector<int>> Seed(int s) const {
    const Candidate& cs = c_[s];
    const int r = Neighbour(s, cs.e1), l = Neighbour(s, -cs.e1), u = Neighbour(s, cs.e2), d = Neighbour(s, -cs.e2);
    if (r < 0 || l < 0 || u < 0 || d < 0) return {};
    const double dr = (c_[r].p - cs.p).norm(), dl = (c_[l].p - cs.p).norm();
    const double du = (c_[u].p - cs.p).norm(), dd = (c_[d].p - cs.p).norm();
    if (dr / dl > 2 || dl / dr > 2 || du / dd > 2 || dd / du > 2) return {};
    std::vector<char> used(c_.size(), 0);
    for (int k : {s, r, l, u, d}) used[k] = 1;
    auto corner = [&](int a, int b) {
      const Vec2d pred = c_[a].p + c_[b].p - cs.p;
      const double tol = 0.3 * std::min((c_[a].p - cs.p).norm(), (c_[b].p - cs.p).norm());
      const int k = Nearest(pred, tol, used);
      if (k >= 0) used[k] = 1;
      return k;
    };
    const int ul = corner(u, l), ur = corner(u, r), dl_ = corner(d, l), dr_ = corner(d, r);
    if (ul < 0 || ur < 0 || dl_ < 0 || dr_ < 0) return {};
    return {{dl_, d, dr_}, {l, s, r}, {ul, u, ur}};
  }

  // Adds whole rows / columns while every new corner is found where the grid predicts it.
  void Grow(std::vector<std::vector<int>>* grid) const {
    std::vector<char> used(c_.size(), 0);
    for (const auto& row : *grid)
      for (int k : row) used[k] = 1;
    for (bool grew = true; grew;) {
      grew = false;
      for (int side = 0; side < 4; ++side) {
        auto& g = *grid;
        const int rows = static_cast<int>(g.size()), cols = static_cast<int>(g[0].size());
        const bool add_col = side < 2;
        const int new_cols = cols + (add_col ? 1 : 0), new_rows = rows + (add_col ? 0 : 1);
        if (std::max(new_cols, new_rows) > max_long_ || std::min(new_cols, new_rows) > max_short_) continue;
        const int n = add_col ? rows : cols;
        std::vector<int> added(n, -1);
        std::vector<char> used_now = used;
        bool ok = true;
        for (int k = 0; k < n && ok; ++k) {
          // The line of existing corners towards the new one: a (nearest to the edge), b, c.
          auto at = [&](int step) -> const Vec2d& {
            if (side == 0) return c_[g[k][cols - 1 - step]].p;
            if (side == 1) return c_[g[k][step]].p;
            if (side == 2) return c_[g[rows - 1 - step][k]].p;
            return c_[g[step][k]].p;
          };
          const int len = add_col ? cols : rows;
          const Vec2d a = at(0), b = at(1);
          const Vec2d linear = 2 * a - b;
          const Vec2d pred = len >= 3 ? Vec2d(3 * a - 3 * b + at(2)) : linear;
          const double spacing = (a - b).norm();
          int q = Nearest(pred, 0.35 * spacing, used_now);
          // The quadratic extrapolation follows the mirror's distortion but multiplies the candidates' own error
          // (3 a - 3 b + c: up to seven times it). On small squares (15 px at 1375 x 1100) that error, about
          // half a pixel from the candidates' coarse refinement, can put it more than 0.35 spacing from the
          // corner; the straight extrapolation (three times the error) then still finds it.
          if (q < 0 && len >= 3) q = Nearest(linear, 0.35 * spacing, used_now);
          if (q < 0 || !HasEdgeAlong(c_[q], c_[q].p - a, 20 * kPi / 180)) {
            ok = false;
            break;
          }
          const double step = (c_[q].p - a).norm();
          if (step < 0.4 * spacing || step > 2.0 * spacing) ok = false;
          added[k] = q, used_now[q] = 1;
        }
        if (!ok) continue;
        used = used_now;
        if (side == 0)
          for (int k = 0; k < rows; ++k) g[k].push_back(added[k]);
        else if (side == 1)
          for (int k = 0; k < rows; ++k) g[k].insert(g[k].begin(), added[k]);
        else if (side == 2)
          g.push_back(added);
        else
          g.insert(g.begin(), added);
        grew = true;
      }
    }
  }

 private:
  const std::vector<Candidate>& c_;
  int max_long_, max_short_;
};

// The checker test of a grid of candidates: the squares between four corners must be flat and alternate dark
// and bright. Each square is sampled at its centre and 0.3 of the way to each corner (bilinear on the 8-bit
// image): its level is their mean, its spread their range; the squares of each parity ((i + j) even or odd) form
// one class. A grid passes when
//   - the class means differ by at least min_contrast (grey, in [0, 1]) and by at least three times the spread
//     of the squares' levels within the classes,
//   - each square lies on its class's side of the midway level (every square of a grid of fewer than 10, 90 %
//     of a larger one), and
//   - the squares are flat: their median spread is at most half the contrast.
// Saddle points in noise or texture form grids that fail it: their squares are neither flat nor alternating.
struct CheckerTest {
  bool pass = false;
  double consistent = 0;  // fraction of squares on their class's side
  double contrast = 0;    // difference of the class means, grey in [0, 1]
};
CheckerTest TestChecker(const cv::Mat& grey, const std::vector<Candidate>& c, const std::vector<std::vector<int>>& g,
                        double min_contrast) {
  const auto sample = [&](const Vec2d& p) {
    const int x0 = static_cast<int>(std::floor(p.x())), y0 = static_cast<int>(std::floor(p.y()));
    if (x0 < 0 || y0 < 0 || x0 + 1 >= grey.cols || y0 + 1 >= grey.rows) return std::nan("");
    const double ax = p.x() - x0, ay = p.y() - y0;
    const uint8_t* r0 = grey.ptr<uint8_t>(y0);
    const uint8_t* r1 = grey.ptr<uint8_t>(y0 + 1);
    return ((1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x0 + 1]) + ay * ((1 - ax) * r1[x0] + ax * r1[x0 + 1])) / 255.0;
  };
  std::vector<std::pair<int, double>> squares;  // parity, level
  std::vector<double> spreads;
  for (size_t j = 0; j + 1 < g.size(); ++j)
    for (size_t i = 0; i + 1 < g[j].size(); ++i) {
      const Vec2d corners[4] = {c[g[j][i]].p, c[g[j][i + 1]].p, c[g[j + 1][i]].p, c[g[j + 1][i + 1]].p};
      const Vec2d centre = 0.25 * (corners[0] + corners[1] + corners[2] + corners[3]);
      double s[5] = {sample(centre), 0, 0, 0, 0};
      for (int k = 0; k < 4; ++k) s[k + 1] = sample(centre + 0.3 * (corners[k] - centre));
      const double sum = s[0] + s[1] + s[2] + s[3] + s[4];
      if (!std::isfinite(sum)) continue;
      squares.emplace_back(static_cast<int>((i + j) % 2), sum / 5);
      spreads.push_back(*std::max_element(s, s + 5) - *std::min_element(s, s + 5));
    }
  CheckerTest t;
  double mean[2] = {0, 0};
  int n[2] = {0, 0};
  for (const auto& [parity, level] : squares) mean[parity] += level, ++n[parity];
  if (n[0] == 0 || n[1] == 0) return t;
  mean[0] /= n[0], mean[1] /= n[1];
  t.contrast = std::abs(mean[0] - mean[1]);
  double within = 0;
  for (const auto& [parity, level] : squares) within += (level - mean[parity]) * (level - mean[parity]);
  within = std::sqrt(within / squares.size());
  const double mid = 0.5 * (mean[0] + mean[1]);
  const int bright = mean[0] > mean[1] ? 0 : 1;
  int on_side = 0;
  for (const auto& [parity, level] : squares) on_side += (parity == bright) == (level > mid);
  t.consistent = double(on_side) / squares.size();
  std::nth_element(spreads.begin(), spreads.begin() + spreads.size() / 2, spreads.end());
  const double median_spread = spreads[spreads.size() / 2];
  t.pass = t.contrast >= min_contrast && t.contrast >= 3 * within && median_spread <= 0.5 * t.contrast &&
           (squares.size() < 10 ? on_side == static_cast<int>(squares.size()) : t.consistent >= 0.9);
  return t;
}

std::vector<Candidate> Candidates(const cv::Mat& grey, const CheckerboardDetectOptions& o) {
  cv::Mat f;
  grey.convertTo(f, CV_32F, 1.0 / 255);
  cv::Mat light;
  cv::GaussianBlur(f, light, cv::Size(0, 0), 0.8);
  std::vector<Candidate> all;
  // Two scales: sigma 1.5 px on the image and on the image reduced by two (sigma 3 px at full resolution).
  cv::Mat level = f;
  for (int l = 0; l < 2; ++l) {
    if (l == 1) cv::pyrDown(f, level);
    const double sigma = 1.5, scale = l == 0 ? 1.0 : 2.0;
    cv::Mat b, xx, yy, xy;
    cv::GaussianBlur(level, b, cv::Size(0, 0), sigma);
    cv::Sobel(b, xx, CV_32F, 2, 0, 3, 0.25);
    cv::Sobel(b, yy, CV_32F, 0, 2, 3, 0.25);
    cv::Sobel(b, xy, CV_32F, 1, 1, 3, 0.25);
    cv::Mat s = (xy.mul(xy) - xx.mul(yy)) * (sigma * sigma * sigma * sigma);
    const int r = 2;
    cv::Mat dil;
    cv::dilate(s, dil, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * r + 1, 2 * r + 1)));
    const double floor_response = 0.02 * o.min_contrast * o.min_contrast;
    const double radius = std::max(3.5, 2.0 * sigma * scale);
    for (int y = r; y < s.rows - r; ++y) {
      const float* sr = s.ptr<float>(y);
      const float* dr = dil.ptr<float>(y);
      for (int x = r; x < s.cols - r; ++x) {
        if (sr[x] < floor_response || sr[x] < dr[x]) continue;
        Candidate c;
        c.p = Vec2d(x * scale, y * scale);
        if (o.valid && !o.valid(c.p)) continue;
        if (!VerifyCorner(light, c.p, radius, o.min_contrast, &c.e1, &c.e2)) continue;
        c.response = sr[x];
        all.push_back(c);
      }
    }
  }
  if (all.empty()) return all;
  // Sub-pixel position of each candidate, then one candidate per place (the stronger).
  std::vector<cv::Point2f> pts;
  for (const auto& c : all) pts.emplace_back(static_cast<float>(c.p.x()), static_cast<float>(c.p.y()));
  cv::cornerSubPix(grey, pts, cv::Size(3, 3), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 20, 0.01));
  for (size_t k = 0; k < all.size(); ++k) {
    const Vec2d q(pts[k].x, pts[k].y);
    if ((q - all[k].p).norm() < 2.5) all[k].p = q;
  }
  std::sort(all.begin(), all.end(), [](const Candidate& a, const Candidate& b) { return a.response > b.response; });
  std::vector<Candidate> kept;
  for (const auto& c : all) {
    bool dup = false;
    for (const auto& k : kept)
      if ((k.p - c.p).squaredNorm() < 2.0 * 2.0) {
        dup = true;
        break;
      }
    if (!dup) kept.push_back(c);
  }
  return kept;
}

}  // namespace

std::vector<char> ProveGridLabels(const std::vector<Vec2d>& p, int cols, int rows, double max_fraction, double min_px,
                                  std::vector<double>* removed_errors, double* worst) {
  std::vector<char> keep(p.size(), 1);
  const auto at = [&](int i, int j) -> const Vec2d* {
    if (i < 0 || j < 0 || i >= cols || j >= rows || !keep[j * cols + i]) return nullptr;
    return &p[j * cols + i];
  };
  // Prediction along direction (di, dj) and the local square size there; false if the line has too few corners.
  const auto predict = [&](int i, int j, int di, int dj, Vec2d* out, double* square) {
    const Vec2d *m1 = at(i - di, j - dj), *p1 = at(i + di, j + dj);
    const Vec2d *m2 = at(i - 2 * di, j - 2 * dj), *p2 = at(i + 2 * di, j + 2 * dj);
    const Vec2d *m3 = at(i - 3 * di, j - 3 * dj), *p3 = at(i + 3 * di, j + 3 * dj);
    if (m1 && p1 && m2 && p2) {
      *out = (-*m2 + 4 * *m1 + 4 * *p1 - *p2) / 6, *square = 0.5 * (*p1 - *m1).norm();
    } else if (m1 && p1) {
      *out = 0.5 * (*m1 + *p1), *square = 0.5 * (*p1 - *m1).norm();
    } else if (m1 && m2 && m3) {
      *out = 3 * *m1 - 3 * *m2 + *m3, *square = (*m1 - *m2).norm();
    } else if (p1 && p2 && p3) {
      *out = 3 * *p1 - 3 * *p2 + *p3, *square = (*p1 - *p2).norm();
    } else {
      return false;
    }
    return true;
  };
  // Relative error of corner (i, j) (the smaller of its two lines'), and the same counting only misses above
  // min_px (what the check acts on: on squares of a few pixels, the corners' own noise is a large fraction).
  const auto error_of = [&](int i, int j, double* acted) {
    double best = HUGE_VAL, best_acted = HUGE_VAL;
    for (const auto& [di, dj] : {std::pair(1, 0), std::pair(0, 1)}) {
      Vec2d pred;
      double square = 0;
      if (!predict(i, j, di, dj, &pred, &square) || !(square > 0)) continue;
      const double miss = (p[j * cols + i] - pred).norm();
      best = std::min(best, miss / square), best_acted = std::min(best_acted, miss <= min_px ? 0.0 : miss / square);
    }
    *acted = best_acted == HUGE_VAL ? 0.0 : best_acted;  // a corner no line predicts cannot be checked
    return best == HUGE_VAL ? 0.0 : best;
  };
  for (;;) {
    int worst_k = -1;
    double worst_e = 0;
    *worst = 0;
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < cols; ++i) {
        if (!keep[j * cols + i]) continue;
        double acted = 0;
        *worst = std::max(*worst, error_of(i, j, &acted));
        if (acted > worst_e) worst_e = acted, worst_k = j * cols + i;
      }
    if (worst_k < 0 || worst_e <= max_fraction) break;
    keep[worst_k] = 0;
    removed_errors->push_back(worst_e);
  }
  return keep;
}

namespace {

// Removes the corners ProveGridLabels rejects from the detection (and their by_edges flags); false, leaving
// the detection to be refused, when more than a fifth of them go.
bool ApplyLabelProof(int cols, int rows, double max_label_error, CheckerboardDetection* det,
                     std::vector<char>* by_edges) {
  std::vector<double> removed;
  const std::vector<char> keep =
      ProveGridLabels(det->pixels, cols, rows, max_label_error, 1.0, &removed, &det->worst_label_error);
  if (removed.empty()) return true;
  det->rejected = static_cast<int>(removed.size());
  det->rejected_reason = std::to_string(removed.size()) + " off their row or column (up to " +
                         FormatNumber("%.2f", *std::max_element(removed.begin(), removed.end())) + " of a square)";
  if (det->rejected * 5 > cols * rows) return false;
  size_t w = 0;
  for (size_t k = 0; k < keep.size(); ++k)
    if (keep[k]) {
      det->pixels[w] = det->pixels[k], det->board_points[w] = det->board_points[k];
      det->indices[w] = det->indices[k], (*by_edges)[w] = (*by_edges)[k], ++w;
    }
  det->pixels.resize(w), det->board_points.resize(w), det->indices.resize(w), by_edges->resize(w);
  det->complete = false;
  return true;
}

// found and status of a labelled grid: complete, partial (when allowed) or too small.
void SetFoundAndStatus(const std::string& dims, int total, const CheckerboardDetectOptions& o,
                       CheckerboardDetection* det) {
  const int kept = static_cast<int>(det->pixels.size());
  const std::string trimmed = det->rejected > 0 ? ", " + det->rejected_reason + " removed" : "";
  if (det->complete) {
    det->found = true;
    det->status = "complete " + dims;
  } else if (kept < o.min_corners) {
    det->status = "grid " + dims + " too small (" + std::to_string(kept) + " corners, at least " +
                  std::to_string(o.min_corners) + " needed" + trimmed + ")";
  } else if (!o.allow_partial) {
    det->status = "partial " + dims + " (" + std::to_string(kept) + " of " + std::to_string(total) + trimmed +
                  ") and partial boards are not allowed";
  } else {
    det->found = true;
    det->status = "partial " + dims + " (" + std::to_string(kept) + " of " + std::to_string(total) + trimmed + ")";
  }
}

}  // namespace

CheckerboardDetection DetectCheckerboard(const cv::Mat& image, const CheckerboardDetectOptions& o) {
  o.Check("checkerboard detection options");
  HOVS_REQUIRE(!image.empty() && image.type() == CV_8UC1, "checkerboard detection",
               "expected a non-empty 8-bit grey image");
  CheckerboardDetection det;
  const auto cand = Candidates(image, o);
  det.candidates = static_cast<int>(cand.size());
  const int max_long = std::max(o.board.cols, o.board.rows), max_short = std::min(o.board.cols, o.board.rows);
  // One row or column more than the board is allowed to grow, so that a board larger than described is noticed.
  GridGrower grower(cand, max_long + 1, max_short + 1);
  std::vector<std::vector<int>> best;
  std::vector<char> in_best(cand.size(), 0);
  const int total = o.board.cols * o.board.rows;
  int tried = 0, not_checker = 0;
  for (size_t s = 0; s < cand.size() && tried < o.max_seeds; ++s) {
    if (in_best[s]) continue;
    auto g = grower.Seed(static_cast<int>(s));
    if (g.empty()) continue;
    ++tried;
    grower.Grow(&g);
    if (!TestChecker(image, cand, g, o.min_contrast).pass) {
      ++not_checker;
      continue;
    }
    const size_t n = g.size() * g[0].size();
    if (best.empty() || n > best.size() * best[0].size()) {
      best = g;
      std::fill(in_best.begin(), in_best.end(), 0);
      for (const auto& row : best)
        for (int k : row) in_best[k] = 1;
      if (static_cast<int>(n) == total) break;
    }
  }
  if (best.empty()) {
    det.status = not_checker > 0 ? "no board: " + std::to_string(not_checker) +
                                       " grids of saddle points whose squares do not alternate dark and bright"
                                 : "no grid: " + std::to_string(det.candidates) +
                                       " saddle candidates, none with four grid neighbours";
    return det;
  }
  // Grid [row][col] -> board axes: the longer grid side along the longer board side when the whole board is seen.
  int rows = static_cast<int>(best.size()), cols = static_cast<int>(best[0].size());
  auto transpose = [&]() {
    std::vector<std::vector<int>> t(cols, std::vector<int>(rows));
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < cols; ++i) t[i][j] = best[j][i];
    best.swap(t);
    std::swap(rows, cols);
  };
  const bool fits = cols <= o.board.cols && rows <= o.board.rows;
  const bool fits_t = rows <= o.board.cols && cols <= o.board.rows;
  if (!fits && !fits_t) {
    det.grid_cols = cols, det.grid_rows = rows;
    det.status = "grid " + std::to_string(cols) + "x" + std::to_string(rows) + " is larger than the " +
                 std::to_string(o.board.cols) + "x" + std::to_string(o.board.rows) +
                 " board: the board description does not match the image";
    return det;
  }
  if (!fits && fits_t)
    transpose();
  else if (fits && fits_t && (cols >= rows) != (o.board.cols >= o.board.rows))
    transpose();
  // Handedness: cross(x axis, y axis) must have the expected sign.
  double cross = 0;
  for (int j = 0; j + 1 < rows; ++j)
    for (int i = 0; i + 1 < cols; ++i) {
      const Vec2d x = cand[best[j][i + 1]].p - cand[best[j][i]].p, y = cand[best[j + 1][i]].p - cand[best[j][i]].p;
      cross += x.x() * y.y() - x.y() * y.x();
    }
  if ((cross > 0 ? 1 : -1) != o.orientation) std::reverse(best.begin(), best.end());
  det.grid_cols = cols, det.grid_rows = rows;
  const int n = rows * cols;
  det.complete = n == total;
  // Sub-pixel refinement with a window scaled to the local square size.
  std::vector<cv::Point2f> pts;
  std::vector<int> windows;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i) {
      const Vec2d p = cand[best[j][i]].p;
      double spacing = 1e30;
      if (i > 0) spacing = std::min(spacing, (cand[best[j][i - 1]].p - p).norm());
      if (i + 1 < cols) spacing = std::min(spacing, (cand[best[j][i + 1]].p - p).norm());
      if (j > 0) spacing = std::min(spacing, (cand[best[j - 1][i]].p - p).norm());
      if (j + 1 < rows) spacing = std::min(spacing, (cand[best[j + 1][i]].p - p).norm());
      const int w = o.subpix_half_window > 0 ? o.subpix_half_window
                                             : std::clamp(static_cast<int>(std::lround(0.35 * spacing)), 2, 11);
      std::vector<cv::Point2f> one = {cv::Point2f(static_cast<float>(p.x()), static_cast<float>(p.y()))};
      cv::cornerSubPix(image, one, cv::Size(w, w), cv::Size(-1, -1),
                       cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 40, 0.001));
      const Vec2d q(one[0].x, one[0].y);
      det.pixels.push_back((q - p).norm() < 0.5 * spacing ? q : p);
      det.board_points.emplace_back(i * o.board.square, j * o.board.square, 0.0);
      det.indices.emplace_back(i, j);
    }
  // Then from the board's edges (calib/checkerboard_edges.h); corners whose lines cannot be measured keep
  // their cornerSubPix position.
  std::vector<char> by_edges(det.pixels.size(), 0);
  if (o.corner_refinement == "edges") {
    std::vector<std::optional<Vec2d>> grid(det.pixels.begin(), det.pixels.end());
    CheckerboardEdgeOptions eo;
    eo.min_contrast = 255.0 * o.min_contrast;
    const auto refined = RefineCheckerboardCornersByEdges(image, cols, rows, &grid, eo);
    for (size_t k = 0; k < grid.size(); ++k) det.pixels[k] = *grid[k], by_edges[k] = refined[k];
  }
  const std::string dims = std::to_string(cols) + "x" + std::to_string(rows);
  if (!ApplyLabelProof(cols, rows, o.max_label_error, &det, &by_edges)) {
    det.status = "grid " + dims + " refused: " + det.rejected_reason + ", its labels are not consistent";
    det.pixels.clear(), det.board_points.clear(), det.indices.clear();
    return det;
  }
  for (char b : by_edges) det.from_edges += b;
  SetFoundAndStatus(dims, total, o, &det);
  if (!det.found) det.pixels.clear(), det.board_points.clear(), det.indices.clear();
  return det;
}

BoardObservation ToObservation(const CheckerboardDetection& detection, const std::string& image_name) {
  BoardObservation o;
  o.image = image_name;
  o.board_points = detection.board_points;
  o.pixels = detection.pixels;
  return o;
}

std::map<std::string, std::string> CalibVersions() { return {{"opencv", cv::getVersionString()}}; }

}  // namespace hovs::calib
