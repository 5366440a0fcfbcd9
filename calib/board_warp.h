// Board flex: a printed board is not quite flat. As mrcal does, its deviation from the plane is modelled by two
// parabolas, one along each board axis, zero at the board's edges and largest at its centre:
//   dz(x, y) = w_x (1 - xn^2) + w_y (1 - yn^2),   xn, yn in [-1, 1] across the board's extent
// (metres; w_x + w_y is the bulge at the centre). One (w_x, w_y) is shared by every image of the board.
#pragma once

#include <algorithm>
#include <array>
#include <vector>

#include "core/types.h"

namespace hovs::calib {

struct BoardExtent {
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;  // the board points' range, metres

  // The extent of every board point of every image (a board seen whole at least once spans the board).
  template <class Observations>
  static BoardExtent Of(const Observations& obs) {
    BoardExtent e{1e30, -1e30, 1e30, -1e30};
    for (const auto& o : obs)
      for (const Vec3d& p : o.board_points)
        e.x0 = std::min(e.x0, p.x()), e.x1 = std::max(e.x1, p.x()), e.y0 = std::min(e.y0, p.y()),
        e.y1 = std::max(e.y1, p.y());
    if (!(e.x1 > e.x0)) e.x0 -= 0.5, e.x1 += 0.5;
    if (!(e.y1 > e.y0)) e.y0 -= 0.5, e.y1 += 0.5;
    return e;
  }

  template <class T>
  Vec3<T> Warped(const Vec3d& p, const T* warp) const {
    const double xn = (2 * p.x() - x0 - x1) / (x1 - x0), yn = (2 * p.y() - y0 - y1) / (y1 - y0);
    return Vec3<T>(T(p.x()), T(p.y()), T(p.z()) + warp[0] * T(1 - xn * xn) + warp[1] * T(1 - yn * yn));
  }

  std::vector<Vec3d> Warped(const std::vector<Vec3d>& points, const std::array<double, 2>& warp) const {
    std::vector<Vec3d> out;
    for (const Vec3d& p : points) out.push_back(Warped<double>(p, warp.data()));
    return out;
  }
};

}  // namespace hovs::calib
