// A calibrated model refitted to the models other tools take (core/generic_models.h: double sphere, extended
// unified, Kannala-Brandt; and the unified model with radial-tangential distortion, Kalibr's omni + radtan), so
// that a hovs calibration can be handed to Basalt, Kalibr, OpenVINS or VINS-Fusion knowing what it costs: the
// source's rays over a grid of its valid domain (the calibrated field) are fitted in pixels, and the fit's error
// over that field is reported (px: where the fitted model puts each grid pixel's ray).
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/any_model.h"
#include "core/generic_models.h"
#include "core/statistics.h"
#include "core/unified.h"

namespace hovs::calib {

struct RefitOptions {
  std::string kind = "ds";  // ds | eucm | kb | omni
  int grid_step_px = 0;     // 0: about 60 grid columns
  int max_iterations = 200;
  // Fit a turn of the frame about the optical axis too: a polynomial model's affine terms hold such a turn (a
  // gauge of its calibration) that the other models cannot; the refit's frame is then the source's turned by
  // axis_rotation_deg (what a relative pose in the source's frame must be composed with).
  bool fit_axis_rotation = true;
  void Check(const std::string& where) const;
};

struct Refit {
  std::string kind;
  std::optional<GenericModel<double>> generic;  // ds, eucm, kb (the tools' frame: OmniFromMirror)
  std::optional<UnifiedModel<double>> unified;  // omni (hovs' mirror frame, as core/unified.h)
  std::vector<std::string> names;               // the parameters, in the tools' order
  std::vector<double> values;
  SampleSummary px;              // error over the source's domain, px
  size_t pixels = 0;             // grid pixels in the source's domain
  size_t outside = 0;            // of those, where the fitted model has no projection
  double field_deg = 0;          // the largest angle from the optical axis in the source's domain
  double axis_rotation_deg = 0;  // the refit's frame: the source's turned by this about the optical axis
  bool converged = false;
};

// Throws hovs::Error for an unknown kind or a source with fewer than 50 grid pixels in its domain.
Refit RefitModel(const AnyModel& source, const RefitOptions& options);

nlohmann::json RefitJson(const Refit& refit);

}  // namespace hovs::calib
