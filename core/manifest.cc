#include "core/manifest.h"

#include <set>
#include <string>

#include "core/error.h"
#include "core/io.h"

namespace hovs {

void CheckDatasetManifest(const nlohmann::json& m, const std::string& source) {
  HOVS_REQUIRE(m.is_object() && m.value("format", "") == "hovs-dataset", source, "not a hovs dataset manifest");
  HOVS_REQUIRE(m.contains("units") && m["units"].is_array() && m.contains("frames") && m["frames"].is_array(), source,
               "the manifest lacks 'units' or 'frames'");
  std::set<std::string> names;
  for (size_t i = 0; i < m["units"].size(); ++i) {
    const auto& u = m["units"][i];
    const std::string where = source + " (units[" + std::to_string(i) + "])";
    HOVS_REQUIRE(u.is_object() && u.contains("name") && u["name"].is_string(), where, "a unit needs a string 'name'");
    HOVS_REQUIRE(names.insert(u["name"].get<std::string>()).second, where, "unit name '", u["name"].get<std::string>(),
                 "' appears twice");
  }
  const auto is_text = [](const nlohmann::json& j, const char* key) {
    return j.contains(key) && j[key].is_string() && !j[key].get<std::string>().empty();
  };
  for (size_t f = 0; f < m["frames"].size(); ++f) {
    const auto& fr = m["frames"][f];
    const std::string wf = "frames[" + std::to_string(f) + "]";
    HOVS_REQUIRE(fr.is_object() && fr.contains("views") && fr["views"].is_array(), source + " (" + wf + ")",
                 "a frame needs a 'views' list");
    for (size_t v = 0; v < fr["views"].size(); ++v) {
      const auto& view = fr["views"][v];
      const std::string key = wf + ".views[" + std::to_string(v) + "]", where = source + " (" + key + ")";
      HOVS_REQUIRE(view.is_object() && is_text(view, "unit") && is_text(view, "image"), where,
                   "a view needs the strings 'unit' and 'image'");
      HOVS_REQUIRE(names.count(view["unit"].get<std::string>()) == 1, where, "unit '",
                   view["unit"].get<std::string>(), "' is not among the manifest's units");
      if (view.contains("ground_truth")) {
        const auto& gt = view["ground_truth"];
        HOVS_REQUIRE(gt.is_object() && is_text(gt, "exr") && is_text(gt, "sidecar"), source + " (" + key + ".ground_truth)",
                     "needs the strings 'exr' and 'sidecar'");
      }
      if (view.contains("device_ns"))
        HOVS_REQUIRE(view["device_ns"].is_number_unsigned(), source + " (" + key + ".device_ns)",
                     "must be an unsigned integer");
    }
  }
}

nlohmann::json LoadDatasetManifest(const std::filesystem::path& path) {
  auto m = nlohmann::json::parse(ReadFile(path), nullptr, false);
  HOVS_REQUIRE(!m.is_discarded(), path.string(), "not a hovs dataset manifest (not JSON)");
  CheckDatasetManifest(m, path.string());
  return m;
}

}  // namespace hovs
