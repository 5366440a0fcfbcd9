// The optics of a design (optics/README.md has the definitions): the blur atlas over elevation x scene distance,
// the best single focus over the field band and the scene distances, the geometric constraints again at that
// focus (the image scale follows the focus), the depth of field per elevation, the trade of worst blur against
// f-number, spot diagrams, through-focus and MTF curves; written as blur.csv, figures and a report section.
//
// The blur figures are taken at the focus in force when the config gives one (lens.focus_distance), else (focused
// at infinity, the article's pinhole) at the best single focus: blur.csv's focus_distance_m says which.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "design/design.h"
#include "optics/focus.h"
#include "results/html.h"

namespace hovs::design {

struct FNumberTrade {
  double f_number = 0, best_focus = 0, worst_rms = 0;
  double airy_radius_px = 0;  // 1.22 lambda N_w / pitch: the diffraction spot's first dark ring
};

struct DesignOptics {
  std::string label;  // which design ("integer-mm optimum", a mirror's name, ...)
  DesignPoint p;
  Metrics metrics;   // at the focus in force
  ThinLens lens;     // the config's lens
  double focus = 0;  // the focus of the blur figures (in force, or the best single focus)
  bool focus_given = false;
  std::vector<double> elevations, distances;  // the atlas grid (distances from F1; the last one +inf)
  std::vector<optics::FieldBlur> atlas;       // elevation-major: atlas[i * distances.size() + j]
  optics::SingleFocus best;                   // over the atlas
  optics::DepthOfFocus depth_of_focus;        // about `best`, tolerance blur.limit_px
  double worst_rms = 0;                       // over the atlas at `focus`
  Metrics at_best;                            // the design's metrics with the lens at the best single focus
  std::vector<ConstraintValue> constraints_at_best;
  std::vector<optics::DepthOfField> dof;  // per elevation at `focus`
  std::vector<FNumberTrade> trade;
  double f_number_for_limit =
      0;                       // the largest aperture (smallest N) whose worst RMS <= FNumberLimitPx (0: none <= 256)
  bool f_number_auto = false;  // lens.f_number: auto: lens.f_number is the design's choice
  // constraints.max_blur_px on this design: the worst RMS radius over the atlas at `focus` against the limit.
  std::optional<ConstraintValue> blur_constraint;
  std::vector<optics::FieldBlur> spots;  // a 5 x 3 grid of field points, points kept
  std::vector<double> spot_elevations, spot_distances;
  std::vector<std::vector<optics::FocusSample>> through_focus;  // per spot elevation, at the farthest distance
  std::vector<double> through_focus_distances;
};

// With lens.f_number: auto, the f-number is chosen first (the widest aperture whose worst RMS radius meets
// BlurSpec::FNumberLimitPx on the atlas) and every figure is at it.
DesignOptics AnalyseOptics(const DesignPoint& p, const DesignProblem& problem, const std::string& label);

// The best single focus of a design over its field band and the blur's scene distances (the atlas's grid), and
// the depth of focus about it for a tolerance of blur.limit_px: the prediction a focus loop is checked against.
struct FocusPrediction {
  optics::SingleFocus best;
  optics::DepthOfFocus depth;
  double lower_deg = 0, upper_deg = 0;  // the field band
};
FocusPrediction PredictFocus(const DesignPoint& p, const DesignProblem& problem);
nlohmann::json FocusPredictionJson(const FocusPrediction& f);

// blur.csv's header and rows (a `mirror` column first when mirror is non-empty).
std::string BlurCsvHeader(bool with_mirror);
std::string BlurCsvRows(const DesignOptics& o, const std::string& mirror = "");
nlohmann::json OpticsJson(const DesignOptics& o);
// Figures under dir/figures/ named by prefix (atlas, spots, through-focus, MTF, trade); returns their file names.
std::vector<std::string> WriteOpticsFigures(const DesignOptics& o, const DesignProblem& problem,
                                            const std::filesystem::path& dir, const std::string& prefix);
// The report's optics section: the statements, the depth of field table and the figures.
void AppendOpticsSection(results::HtmlPage* page, const DesignOptics& o, const DesignProblem& problem,
                         const std::vector<std::string>& figures);
// Lines for summary.txt.
std::string OpticsSummary(const DesignOptics& o, const DesignProblem& problem);

}  // namespace hovs::design
