// Shared by the subcommands: calibrated models from files, dataset manifests, 8-bit images from any
// OpenImageIO format.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calib/model_io.h"  // LoadPolynomialModelFile
#include "core/any_model.h"
#include "core/manifest.h"
#include "depth/stereo.h"  // LoadDatasetManifest, used with the models by every command
#include "unwrap/remap.h"
#include "unwrap/rig_mapping.h"

namespace hovs::apps {

// The image size a model file may lack (OpenCV's omni_calibration sample writes none); 0 x 0: none given.
struct ImageSize {
  int width = 0, height = 0;
};

// A calibrated model file as a handle: calib_results.txt -> polynomial; a hovs calibration.json -> its physical
// model (mirror + camera pose, through the exact projection) when it has one and prefer is "auto" or "physical",
// else its polynomial model. prefer: auto | physical | polynomial.
// An OpenCV omnidir YAML or XML file -> unified (its size, or `size` when it has none).
AnyModel LoadCalibratedModel(const std::filesystem::path& path, const std::string& prefer = "auto",
                             double scene_distance = 10.0, ImageSize size = {});

// The model named by --model: a scene YAML or a dataset manifest (the exact rig of `unit`, default the first),
// calib_results.txt, an omnidir YAML or XML file, a Kalibr camchain, a MEI YAML, or a hovs calibration.json
// (LoadCalibratedModel). Throws naming the file.
AnyModel LoadModelSpec(const std::string& spec, const std::string& unit, double scene_distance, ImageSize size = {});

// Every unit of a multi-unit model file, by name: a scene YAML or a dataset manifest (each unit's exact rig), a
// Kalibr camchain (cam0, cam1, ...). Throws naming the file when it holds one camera only.
std::vector<std::string> ModelUnitNames(const std::string& spec);

// Every unit of a multi-unit model file as a rig unit: name, model and pose in the rig (unit 0's mirror frame),
// from a scene YAML or dataset manifest (their units' world poses); a Kalibr camchain's cameras have no pose here.
std::vector<unwrap::RigUnitModel> LoadRigUnits(const std::string& spec, double scene_distance);

// The stereo rig of two units of a scene YAML or a dataset manifest: their exact models and the relative pose
// their world poses give, or the calibrated one of `stereo_json` (hovs stereo-calibrate's stereo.json). Throws
// naming the file or unit.
depth::StereoRig LoadStereoRig(const std::string& spec, const std::string& left, const std::string& right,
                               double scene_distance, const std::string& stereo_json);

// The frames an --input names: an image, a folder of images (each frame named after its file; two of one name
// are refused), or a dataset manifest (every view of `unit`, default the first; frames named frame<id>).
struct InputFrame {
  std::string name;
  std::filesystem::path image;
};
std::vector<InputFrame> ListInputs(const std::string& input, const std::string& unit);

using unwrap::LoadImage8;  // an image file as 8-bit grey or RGB (unwrap/remap.h)

}  // namespace hovs::apps
