// The lens focus of the variable-scale unit: a sharpness measure on the mirror image and the loop that maximises
// it through the focus axis. Every mirror puts the virtual image of the scene at its own distance (about 1.15 x
// the plate height for the reference mirror), so a switch must refocus.
//
// Sharpness: the mean squared gradient (Sobel, after a Gaussian of 1 px that keeps the renderer's and the
// sensor's pixel noise out) over the mirror annulus between 35 % and 95 % of the rim's image radius, where the
// scene is (not the camera's own reflection, not the rim's edge).
// Search: a coarse scan of the focus over [low, high] x the plate height, then a golden-section refinement
// between the coarse maximum's neighbours. Each evaluation moves the focus axis, waits for it and takes an image.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rig/positioning.h"

namespace hovs::rig {

double Sharpness(const TurretImage& image, const TurretSpec& spec, int k);

struct FocusOptions {
  double low = 0.8, high = 1.6;  // bracket, times the mirror's plate height
  int coarse_steps = 13;
  int refine_iterations = 8;
  double settle_timeout = 10;  // s of machine time per move
  void Check(const std::string& where) const;
};

struct FocusResult {
  double focus = 0;                                // the focus distance the axis was left at, m
  double sharpness = 0;                            // there
  std::vector<std::pair<double, double>> samples;  // (focus, sharpness) in the order taken
  int images = 0;
};

// Moves the focus axis of plant's machine; throws hovs::Error naming the focus axis when the sharpness is flat
// (no image structure in the bracket: the lens cannot be focused there).
FocusResult FocusLens(Plant& plant, const TurretSpec& spec, const FocusOptions& options);

// What the optics predict for mirror k with the machine's camera and lens (design/optics_report.h PredictFocus,
// optics/README.md): the best single focus over the mirror's field for scene distances 1 m to infinity, and the
// depth of focus about it for a tolerance of 1 px (full-resolution pixels). Empty without a lens (a pinhole).
struct PredictedFocus {
  double best = 0, near = 0, far = 0;  // focus distances, m from the lens
  double worst_rms_px = 0, tolerance_px = 0;
  bool Contains(double focus) const { return focus >= near && focus <= far; }
};
std::optional<PredictedFocus> PredictFocus(const TurretSpec& spec, int k);
// " (predicted best 0.1537 m, depth of focus 0.1490 .. 0.1590 m: within)" for a focus the loop found on mirror
// k; empty without a lens.
std::string FocusAgainstPrediction(const TurretSpec& spec, int k, double focus);

}  // namespace hovs::rig
