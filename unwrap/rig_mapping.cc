#include "unwrap/rig_mapping.h"

#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/io.h"

namespace hovs::unwrap {
namespace {

constexpr char kRigMagic[8] = {'H', 'O', 'V', 'S', 'R', 'I', 'G', '\0'};
constexpr uint32_t kRigVersion = 1;

template <class T>
void Put(std::string* s, const T& v) {
  s->append(reinterpret_cast<const char*>(&v), sizeof v);
}

template <class T>
T Get(const std::string& data, size_t* pos, const std::string& where, const char* what) {
  HOVS_REQUIRE(*pos + sizeof(T) <= data.size(), where, "truncated (", what, ")");
  T v;
  std::memcpy(&v, data.data() + *pos, sizeof(T));
  *pos += sizeof(T);
  return v;
}

}  // namespace

int ResolveUnit(const ViewSpec& view, const std::vector<RigUnitModel>& units) {
  HOVS_REQUIRE(!units.empty(), "view " + view.name, "no unit to take it from");
  if (view.unit.empty()) return 0;
  for (size_t u = 0; u < units.size(); ++u)
    if (units[u].name == view.unit) return static_cast<int>(u);
  const bool digits = view.unit.find_first_not_of("0123456789") == std::string::npos && view.unit.size() < 6;
  if (digits && std::stoi(view.unit) < static_cast<int>(units.size())) return std::stoi(view.unit);
  std::string names;
  for (size_t u = 0; u < units.size(); ++u) names += (u ? ", " : "") + units[u].name + " (" + std::to_string(u) + ")";
  throw Error("view " + view.name,
              "names unit '" + view.unit + "', which the rig does not have (it has " + names + ")");
}

RigMapping BuildRigMapping(const std::vector<RigUnitModel>& units, const Layout& layout, const RemapOptions& options,
                           const std::string& versions_json) {
  layout.Check("layout " + layout.name);
  std::vector<int> unit_of;
  for (const auto& v : layout.views) unit_of.push_back(ResolveUnit(v, units));
  RigMapping m;
  std::vector<int> slot(units.size(), -1);  // rig unit -> index into m.units
  std::vector<Layout> per_unit;
  for (size_t k = 0; k < layout.views.size(); ++k) {
    const int u = unit_of[k];
    if (slot[u] < 0) {
      slot[u] = static_cast<int>(m.units.size());
      m.units.push_back(units[u].name);
      per_unit.emplace_back();
      per_unit.back().name = layout.name + ":" + units[u].name;
    }
    m.order.emplace_back(slot[u], static_cast<int>(per_unit[slot[u]].views.size()));
    per_unit[slot[u]].views.push_back(layout.views[k]);
  }
  for (size_t s = 0; s < m.units.size(); ++s) {
    int u = 0;
    while (units[u].name != m.units[s]) ++u;
    m.tables.push_back(BuildRemapTable(units[u].model, per_unit[s], options, versions_json));
  }
  nlohmann::json order = nlohmann::json::array();
  for (const auto& [u, v] : m.order) order.push_back({u, v});
  m.header = nlohmann::json({{"layout", layout.name},
                             {"units", m.units},
                             {"order", order},
                             {"versions", nlohmann::json::parse(versions_json)}})
                 .dump(1);
  return m;
}

void SaveRigMapping(const std::filesystem::path& path, const RigMapping& m) {
  CheckOutputFile(path, std::string(kRigMagic, sizeof kRigMagic), "a hovs rig mapping file");
  std::string s(kRigMagic, sizeof kRigMagic);
  Put(&s, kRigVersion);
  Put(&s, static_cast<uint32_t>(m.header.size()));
  s += m.header;
  Put(&s, static_cast<uint32_t>(m.tables.size()));
  for (const auto& t : m.tables) {
    const std::string bytes = SerializeRemapTable(t);
    Put(&s, static_cast<uint64_t>(bytes.size()));
    s += bytes;
  }
  WriteFileAtomic(path, s);
}

bool IsRigMappingFile(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  char head[sizeof kRigMagic] = {0};
  return f.read(head, sizeof head) && std::memcmp(head, kRigMagic, sizeof kRigMagic) == 0;
}

RigMapping LoadRigMapping(const std::filesystem::path& path) {
  const std::string where = path.string();
  const std::string data = ReadFile(path);
  HOVS_REQUIRE(data.size() >= 16 && std::memcmp(data.data(), kRigMagic, sizeof kRigMagic) == 0, where,
               "not a hovs rig mapping file (bad magic)");
  size_t pos = sizeof kRigMagic;
  const uint32_t version = Get<uint32_t>(data, &pos, where, "version");
  HOVS_REQUIRE(version == kRigVersion, where, "rig mapping format version ", version,
               " is not supported (this hovs reads version ", kRigVersion, "); rebuild the mapping");
  const uint32_t hn = Get<uint32_t>(data, &pos, where, "header length");
  HOVS_REQUIRE(pos + hn <= data.size(), where, "truncated (header)");
  RigMapping m;
  m.header = data.substr(pos, hn);
  pos += hn;
  nlohmann::json h;
  try {
    h = nlohmann::json::parse(m.header);
    m.units = h.at("units").get<std::vector<std::string>>();
    for (const auto& e : h.at("order")) m.order.emplace_back(e.at(0).get<int>(), e.at(1).get<int>());
  } catch (const nlohmann::json::exception& e) { throw Error(where, std::string("bad header: ") + e.what()); }
  const uint32_t n = Get<uint32_t>(data, &pos, where, "table count");
  HOVS_REQUIRE(n == m.units.size() && n >= 1 && n <= 64, where, n, " tables for ", m.units.size(), " units");
  for (uint32_t k = 0; k < n; ++k) {
    const uint64_t size = Get<uint64_t>(data, &pos, where, "table size");
    HOVS_REQUIRE(size <= data.size() - pos, where, "truncated (unit ", m.units[k], "'s table)");
    m.tables.push_back(ParseRemapTable(data.substr(pos, size), where + " (unit " + m.units[k] + ")"));
    pos += size;
  }
  HOVS_REQUIRE(pos == data.size(), where, data.size() - pos, " bytes after the last table");
  std::vector<std::vector<bool>> used(n);
  for (uint32_t k = 0; k < n; ++k) used[k].assign(m.tables[k].views.size(), false);
  for (const auto& [u, v] : m.order) {
    HOVS_REQUIRE(u >= 0 && u < int(n) && v >= 0 && v < int(m.tables[u].views.size()) && !used[u][v], where,
                 "the header's view order does not match the tables");
    used[u][v] = true;
  }
  for (const auto& t : used)
    for (const bool b : t) HOVS_REQUIRE(b, where, "a table's view is missing from the header's order");
  return m;
}

RigRemapper::RigRemapper(const RigMapping& mapping) : mapping_(mapping) {
  for (const auto& t : mapping_.tables) remappers_.push_back(std::make_unique<Remapper>(t));
}

void RigRemapper::Run(const std::vector<ImageView>& frames, Interpolation interp, std::vector<Image8>* outputs) {
  HOVS_REQUIRE(frames.size() == mapping_.units.size(), "rig remap", "the mapping takes ", mapping_.units.size(),
               " frames (one per unit), not ", frames.size());
  for (size_t u = 0; u < frames.size(); ++u) {
    const RemapTable& t = mapping_.tables[u];
    HOVS_REQUIRE(frames[u].width == t.source_width && frames[u].height == t.source_height, "unit " + mapping_.units[u],
                 "the frame is ", frames[u].width, " x ", frames[u].height, " but this unit's mapping is for ",
                 t.source_width, " x ", t.source_height);
    HOVS_REQUIRE(frames[u].format == frames[0].format, "unit " + mapping_.units[u], "its frame is ",
                 ToString(frames[u].format), " but unit ", mapping_.units[0], "'s is ", ToString(frames[0].format),
                 " (a pair needs one pixel format)");
  }
  outputs->resize(mapping_.order.size());
  std::vector<RemapJob> jobs(frames.size());
  for (size_t u = 0; u < frames.size(); ++u) {
    jobs[u].remapper = remappers_[u].get();
    jobs[u].src = frames[u];
    jobs[u].outputs.resize(mapping_.tables[u].views.size());
  }
  for (size_t k = 0; k < mapping_.order.size(); ++k)
    jobs[mapping_.order[k].first].outputs[mapping_.order[k].second] = &(*outputs)[k];
  RunRemappers(jobs, interp);
}

}  // namespace hovs::unwrap
