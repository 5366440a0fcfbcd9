#include "core/manifest.h"

#include <set>
#include <string>

#include "core/error.h"
#include "core/io.h"
#include "core/json.h"

namespace hovs {
namespace {

// The keys each object of a manifest may hold: every key a hovs writer (render, dataset, capture) puts there. A
// key outside the list is a misspelling or a manifest of another tool, refused by name.
const std::set<std::string> kTopKeys = {"format",       "version",
                                        "kind",         "name",
                                        "seed",         "render_seed",
                                        "versions",     "scene",
                                        "units",        "frames",
                                        "boards",       "generator",
                                        "render_stats", "statistics",
                                        "status",       "unpaired_frames",
                                        "writer",       "incomplete_frames",
                                        "note",         "shard"};
const std::set<std::string> kFrameKeys = {"id",   "views",    "world_from_board", "world_from_rig", "render_seconds",
                                          "rays", "checksums"};
const std::set<std::string> kViewKeys = {"unit",      "image",    "ground_truth", "device_ns",
                                         "system_ns", "frame_id", "pixel_format", "width",
                                         "height",    "serial",   "exposure_us",  "gain"};
const std::set<std::string> kTruthKeys = {"exr", "sidecar"};

void OnlyKeys(const nlohmann::json& j, const std::set<std::string>& known, const std::string& where) {
  for (const auto& [key, value] : j.items()) {
    if (known.count(key)) continue;
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    throw Error(where, "unknown key '" + key + "' (known: " + list + ")");
  }
}

// A relative path inside the manifest's folder (ContainedPath's rules), checked without resolving it.
void CheckRelativePath(const nlohmann::json& j, const char* key, const std::string& where) {
  HOVS_REQUIRE(j.contains(key) && j[key].is_string() && !j[key].get<std::string>().empty(), where, "needs the string '",
               key, "'");
  ContainedPath(".", j[key].get<std::string>(), where.substr(0, where.size() - 1) + "." + key + ")");
}

// A board's counts and lengths within what a printed target can be (a 1e9-corner board was accepted once).
void CheckBoardFields(const nlohmann::json& b, const std::string& where) {
  HOVS_REQUIRE(b.is_object(), where, "a board must be an object");
  for (const char* key : {"inner_corners", "squares", "markers"}) {
    if (!b.contains(key)) continue;
    const auto& v = b[key];
    HOVS_REQUIRE(v.is_array() && v.size() == 2 && v[0].is_number_integer() && v[1].is_number_integer() &&
                     v[0].get<int64_t>() >= 1 && v[1].get<int64_t>() >= 1 && v[0].get<int64_t>() <= 1000 &&
                     v[1].get<int64_t>() <= 1000,
                 where + "." + key, "must be two integers in 1..1000");
  }
  for (const char* key : {"square", "marker_length", "width", "height"})
    if (b.contains(key))
      HOVS_REQUIRE(b[key].is_number() && b[key].get<double>() > 0 && b[key].get<double>() <= 100, where + "." + key,
                   "must be a length in (0, 100] m");
  if (b.contains("separation"))
    HOVS_REQUIRE(
        b["separation"].is_number() && b["separation"].get<double>() >= 0 && b["separation"].get<double>() <= 100,
        where + ".separation", "must be a length in [0, 100] m");
}

}  // namespace

void CheckDatasetManifest(const nlohmann::json& m, const std::string& source) {
  HOVS_REQUIRE(m.is_object() && JsonText(m, "format") == "hovs-dataset", source, "not a hovs dataset manifest");
  OnlyKeys(m, kTopKeys, source);
  HOVS_REQUIRE(
      m.contains("version") && m["version"].is_number_integer() && m["version"].get<int64_t>() == kManifestVersion,
      source + " (version)", "this hovs reads dataset manifests of version ", kManifestVersion, " (got ",
      m.contains("version") ? m["version"].dump() : std::string("none"), ")");
  HOVS_REQUIRE(m.contains("units") && m["units"].is_array() && m.contains("frames") && m["frames"].is_array(), source,
               "the manifest lacks 'units' or 'frames'");
  std::set<std::string> names;
  for (size_t i = 0; i < m["units"].size(); ++i) {
    const auto& u = m["units"][i];
    const std::string where = source + " (units[" + std::to_string(i) + "])";
    HOVS_REQUIRE(u.is_object() && u.contains("name") && u["name"].is_string() && !u["name"].get<std::string>().empty(),
                 where, "a unit needs a non-empty string 'name'");
    HOVS_REQUIRE(names.insert(u["name"].get<std::string>()).second, where, "unit name '", u["name"].get<std::string>(),
                 "' appears twice");
  }
  const auto is_text = [](const nlohmann::json& j, const char* key) {
    return j.contains(key) && j[key].is_string() && !j[key].get<std::string>().empty();
  };
  if (m.contains("boards")) {
    HOVS_REQUIRE(m["boards"].is_array() && m["boards"].size() <= 64, source + " (boards)", "must be a list of boards");
    for (size_t b = 0; b < m["boards"].size(); ++b)
      CheckBoardFields(m["boards"][b], source + " (boards[" + std::to_string(b) + "])");
  }
  std::set<int64_t> ids;
  for (size_t f = 0; f < m["frames"].size(); ++f) {
    const auto& fr = m["frames"][f];
    const std::string wf = "frames[" + std::to_string(f) + "]", fwhere = source + " (" + wf + ")";
    HOVS_REQUIRE(fr.is_object() && fr.contains("views") && fr["views"].is_array(), fwhere,
                 "a frame needs a 'views' list");
    OnlyKeys(fr, kFrameKeys, fwhere);
    HOVS_REQUIRE(fr.contains("id") && fr["id"].is_number_integer() && fr["id"].get<int64_t>() >= 0 &&
                     fr["id"].get<int64_t>() < (int64_t(1) << 31),
                 source + " (" + wf + ".id)", "a frame needs a non-negative integer 'id'");
    HOVS_REQUIRE(ids.insert(fr["id"].get<int64_t>()).second, source + " (" + wf + ".id)", "frame id ",
                 fr["id"].get<int64_t>(), " appears twice");
    if (fr.contains("checksums")) {
      HOVS_REQUIRE(fr["checksums"].is_object(), source + " (" + wf + ".checksums)", "expected {file: checksum}");
      for (const auto& [file, sum] : fr["checksums"].items()) {
        const std::string where = source + " (" + wf + ".checksums." + file + ")";
        const std::string text = sum.is_string() ? sum.get<std::string>() : "";
        HOVS_REQUIRE(text.size() == 24 && text.rfind("fnv1a64:", 0) == 0 &&
                         text.find_first_not_of("0123456789abcdef", 8) == std::string::npos,
                     where, "expected \"fnv1a64:<16 hex digits>\"");
        ContainedPath(".", file, where);
      }
    }
    std::set<std::string> units_seen;
    for (size_t v = 0; v < fr["views"].size(); ++v) {
      const auto& view = fr["views"][v];
      const std::string key = wf + ".views[" + std::to_string(v) + "]", where = source + " (" + key + ")";
      HOVS_REQUIRE(view.is_object() && is_text(view, "unit") && is_text(view, "image"), where,
                   "a view needs the strings 'unit' and 'image'");
      OnlyKeys(view, kViewKeys, where);
      HOVS_REQUIRE(names.count(view["unit"].get<std::string>()) == 1, where, "unit '", view["unit"].get<std::string>(),
                   "' is not among the manifest's units");
      HOVS_REQUIRE(units_seen.insert(view["unit"].get<std::string>()).second, where, "a second view of unit '",
                   view["unit"].get<std::string>(), "' in one frame");
      CheckRelativePath(view, "image", where);
      if (view.contains("ground_truth")) {
        const auto& gt = view["ground_truth"];
        const std::string gwhere = source + " (" + key + ".ground_truth)";
        // The EXR is absent where the set was written without per-pixel channels (render.truth_channels: none).
        HOVS_REQUIRE(gt.is_object() && is_text(gt, "sidecar") && (!gt.contains("exr") || is_text(gt, "exr")), gwhere,
                     "needs the string 'sidecar' and, where there is a ground-truth image, the string 'exr'");
        OnlyKeys(gt, kTruthKeys, gwhere);
        if (gt.contains("exr")) CheckRelativePath(gt, "exr", gwhere);
        CheckRelativePath(gt, "sidecar", gwhere);
      }
      if (view.contains("device_ns"))
        HOVS_REQUIRE(view["device_ns"].is_number_unsigned(), source + " (" + key + ".device_ns)",
                     "must be an unsigned integer");
      for (const char* side : {"width", "height"})
        if (view.contains(side))
          HOVS_REQUIRE(
              view[side].is_number_integer() && view[side].get<int64_t>() >= 1 && view[side].get<int64_t>() <= 65535,
              source + " (" + key + "." + side + ")", "must be an integer in 1..65535");
    }
    // A checksum vouches for the file it names, which is verified when read (LoadDatasetManifest). A frame may name
    // files without one (a manifest written by hand or by a tool that does not checksum); merge requires them.
  }
}

nlohmann::json LoadDatasetManifest(const std::filesystem::path& path) {
  const nlohmann::json m = ReadJsonFile(path);
  CheckDatasetManifest(m, path.string());
  // Every file a frame's checksums vouch for is verified when it is read (core/io.h ExpectChecksum).
  for (const auto& fr : m["frames"])
    if (fr.contains("checksums"))
      for (const auto& [file, sum] : fr["checksums"].items())
        ExpectChecksum(path.parent_path() / file, sum.get<std::string>(), path.string());
  return m;
}

std::filesystem::path ManifestPath(const std::filesystem::path& manifest, const nlohmann::json& relative) {
  return manifest.parent_path() / relative.get<std::string>();
}

}  // namespace hovs
