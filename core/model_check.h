// Checks shared by the camera models' Check(): numbers that no real camera has are refused where a model is
// made or loaded, instead of giving blank views or solver failures later.
#pragma once

#include <cmath>
#include <string>

#include "core/error.h"

namespace hovs {

// Focal lengths (and the polynomial's a0) above this many pixels describe no camera.
inline constexpr double kMaxFocalPx = 1e7;
inline constexpr int kMaxModelImageSide = 65535;

// width, height: 0 (unknown) or 1..65535. The centre (cx, cy) finite and, with a known size, within one image
// size of the image's middle.
inline void CheckImageAndCentre(int width, int height, double cx, double cy, const std::string& where) {
  HOVS_REQUIRE(width >= 0 && height >= 0 && width <= kMaxModelImageSide && height <= kMaxModelImageSide, where,
               "image size ", width, " x ", height, " is outside 1..", kMaxModelImageSide, " (0: unknown)");
  HOVS_REQUIRE(std::isfinite(cx) && std::isfinite(cy), where, "the centre must be finite (got ", cx, ", ", cy, ")");
  if (width > 0 && height > 0)
    HOVS_REQUIRE(std::abs(cx - 0.5 * (width - 1)) <= width && std::abs(cy - 0.5 * (height - 1)) <= height, where,
                 "the centre (", cx, ", ", cy, ") px lies far outside the ", width, " x ", height, " image");
}

}  // namespace hovs
