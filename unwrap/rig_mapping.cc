#include "unwrap/rig_mapping.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/io.h"

namespace hovs::unwrap {
namespace {

constexpr char kRigMagic[8] = {'H', 'O', 'V', 'S', 'R', 'I', 'G', '\0'};
constexpr uint32_t kRigVersion = 2;  // 2: blended views (version 1 files have none and still load)

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

namespace {

// The weights of a view of the whole rig (see rig_mapping.h), from its parts' valid pixels and the units' places.
void BlendWeights(const RigMapping& m, const std::vector<RigUnitModel>& units, const ViewSpec& spec, RigBlend* b) {
  const VirtualView<double> view = spec.View();  // the rig frame
  const Vec3d c0 = units[0].unit_from_rig.Inverse().translation, c1 = units[1].unit_from_rig.Inverse().translation;
  Vec3d own = c0 - c1;  // unit 0 owns the azimuths facing away from unit 1
  own.z() = 0;
  HOVS_REQUIRE(own.norm() > 1e-3, "view " + spec.name, "the units are not side by side (their horizontal distance is ",
               own.norm(), " m): a panorama of the rig splits their azimuths between them");
  own.normalize();
  const double ramp = std::sin(kRigBlendDeg * M_PI / 180);
  std::vector<std::vector<float>> mx(2), my(2);
  for (int p = 0; p < 2; ++p) m.tables[b->parts[p].first].DecodeView(b->parts[p].second, &mx[p], &my[p]);
  const int W = view.width, H = view.height;
  b->weights.assign(2, std::vector<uint8_t>(size_t(W) * H, 0));
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const size_t i = size_t(y) * W + x;
      Vec3d d;
      double f0 = 0.5;
      if (view.MirrorFromImg(Vec2d(x, y), &d) && Vec2d(d.x(), d.y()).norm() > 1e-9) {
        const double s = Vec2d(d.x(), d.y()).normalized().dot(Vec2d(own.x(), own.y()));
        f0 = std::clamp((s + ramp) / (2 * ramp), 0.0, 1.0);
      }
      const double v0 = mx[0][i] >= 0, v1 = mx[1][i] >= 0;
      double w0 = v0 * f0, w1 = v1 * (1 - f0);
      if (w0 + w1 <= 0) w0 = v0, w1 = v1;  // the other unit fills in where one has no pixel
      if (w0 + w1 <= 0) continue;
      const int q0 = static_cast<int>(std::lround(255 * w0 / (w0 + w1)));
      b->weights[0][i] = static_cast<uint8_t>(q0), b->weights[1][i] = static_cast<uint8_t>(255 - q0);
    }
}

}  // namespace

RigMapping BuildRigMapping(const std::vector<RigUnitModel>& units, const Layout& layout, const RemapOptions& options,
                           const std::string& versions_json) {
  layout.Check("layout " + layout.name);
  RigMapping m;
  std::vector<int> slot(units.size(), -1);  // rig unit -> index into m.units
  std::vector<Layout> per_unit;
  const auto add = [&](int u, const ViewSpec& spec) {  // returns (slot, view index)
    if (slot[u] < 0) {
      slot[u] = static_cast<int>(m.units.size());
      m.units.push_back(units[u].name);
      per_unit.emplace_back();
      per_unit.back().name = layout.name + ":" + units[u].name;
    }
    per_unit[slot[u]].views.push_back(spec);
    return std::make_pair(slot[u], static_cast<int>(per_unit[slot[u]].views.size()) - 1);
  };
  std::vector<int> blend_view;  // per blend, its layout view
  for (size_t k = 0; k < layout.views.size(); ++k) {
    const ViewSpec& spec = layout.views[k];
    if (spec.unit != "all") {
      m.order.push_back(add(ResolveUnit(spec, units), spec));
      continue;
    }
    const std::string where = "view " + spec.name;
    HOVS_REQUIRE(units.size() == 2, where, "a view of the whole rig (unit: all) blends two units; the rig has ",
                 units.size());
    HOVS_REQUIRE(spec.type != ViewProjection::kPerspective, where,
                 "a view of the whole rig is a panorama (cylindrical or longlat)");
    for (const auto& u : units)
      HOVS_REQUIRE(u.has_pose, where, "needs the units' poses, and unit ", u.name,
                   "'s is unknown (give a scene YAML or a dataset manifest)");
    RigBlend b;
    for (int u = 0; u < 2; ++u) {
      ViewSpec su = spec;
      su.unit = units[u].name;
      su.pole = units[u].unit_from_rig.rotation * spec.pole;
      b.parts.push_back(add(u, su));
    }
    m.order.emplace_back(-1, static_cast<int>(m.blends.size()));
    m.blends.push_back(std::move(b));
    blend_view.push_back(static_cast<int>(k));
  }
  for (size_t s = 0; s < m.units.size(); ++s) {
    int u = 0;
    while (units[u].name != m.units[s]) ++u;
    m.tables.push_back(BuildRemapTable(units[u].model, per_unit[s], options, versions_json));
  }
  for (size_t b = 0; b < m.blends.size(); ++b) { BlendWeights(m, units, layout.views[blend_view[b]], &m.blends[b]); }
  nlohmann::json order = nlohmann::json::array(), blends = nlohmann::json::array();
  for (const auto& [u, v] : m.order) order.push_back({u, v});
  for (const auto& b : m.blends)
    blends.push_back({{b.parts[0].first, b.parts[0].second}, {b.parts[1].first, b.parts[1].second}});
  m.header = nlohmann::json({{"layout", layout.name},
                             {"units", m.units},
                             {"order", order},
                             {"blends", blends},
                             {"blend_ramp_deg", kRigBlendDeg},
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
  Put(&s, static_cast<uint32_t>(m.blends.size()));
  for (const auto& b : m.blends)
    for (const auto& w : b.weights) {
      Put(&s, static_cast<uint64_t>(w.size()));
      s.append(reinterpret_cast<const char*>(w.data()), w.size());
    }
  Put(&s, MappingChecksum(s.data(), s.size()));
  WriteFileAtomic(path, s);
}

bool IsRigMappingFile(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  char head[sizeof kRigMagic] = {0};
  return f.read(head, sizeof head) && std::memcmp(head, kRigMagic, sizeof kRigMagic) == 0;
}

RigMapping LoadRigMapping(const std::filesystem::path& path) {
  const std::string where = path.string();
  std::string data = ReadFile(path);
  HOVS_REQUIRE(data.size() >= 16 && std::memcmp(data.data(), kRigMagic, sizeof kRigMagic) == 0, where,
               "not a hovs rig mapping file (bad magic)");
  size_t pos = sizeof kRigMagic;
  const uint32_t version = Get<uint32_t>(data, &pos, where, "version");
  HOVS_REQUIRE(version >= 1 && version <= kRigVersion, where, "rig mapping format version ", version,
               " is not supported (this hovs reads versions 1 to ", kRigVersion, "); rebuild the mapping");
  if (version >= 2) {  // the whole file's checksum (each table has its own as well)
    HOVS_REQUIRE(data.size() >= 24, where, "truncated");
    uint64_t stored = 0;
    std::memcpy(&stored, data.data() + data.size() - 8, 8);
    HOVS_REQUIRE(stored == MappingChecksum(data.data(), data.size() - 8), where,
                 "checksum mismatch: the rig mapping file is corrupt or truncated; rebuild it");
    data.resize(data.size() - 8);
  }
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
    if (h.contains("blends"))
      for (const auto& b : h["blends"]) {
        RigBlend rb;
        for (const auto& p : b) rb.parts.emplace_back(p.at(0).get<int>(), p.at(1).get<int>());
        m.blends.push_back(std::move(rb));
      }
  } catch (const nlohmann::json::exception& e) { throw Error(where, std::string("bad header: ") + e.what()); }
  const uint32_t n = Get<uint32_t>(data, &pos, where, "table count");
  HOVS_REQUIRE(n == m.units.size() && n >= 1 && n <= 64, where, n, " tables for ", m.units.size(), " units");
  for (uint32_t k = 0; k < n; ++k) {
    const uint64_t size = Get<uint64_t>(data, &pos, where, "table size");
    HOVS_REQUIRE(size <= data.size() - pos, where, "truncated (unit ", m.units[k], "'s table)");
    m.tables.push_back(ParseRemapTable(data.substr(pos, size), where + " (unit " + m.units[k] + ")"));
    pos += size;
  }
  const uint32_t nb = version >= 2 ? Get<uint32_t>(data, &pos, where, "blend count") : 0;
  HOVS_REQUIRE(nb == m.blends.size(), where, nb, " blends for the header's ", m.blends.size());
  std::vector<std::vector<bool>> used(n);
  for (uint32_t k = 0; k < n; ++k) used[k].assign(m.tables[k].views.size(), false);
  const auto use = [&](int u, int v) {
    HOVS_REQUIRE(u >= 0 && u < int(n) && v >= 0 && v < int(m.tables[u].views.size()) && !used[u][v], where,
                 "the header's view order does not match the tables");
    used[u][v] = true;
  };
  for (auto& b : m.blends) {
    HOVS_REQUIRE(b.parts.size() == 2, where, "a blend of ", b.parts.size(), " parts");
    for (const auto& [u, v] : b.parts) {
      use(u, v);
      const auto& vw = m.tables[u].views[v].view;
      HOVS_REQUIRE(vw.width == m.tables[b.parts[0].first].views[b.parts[0].second].view.width &&
                       vw.height == m.tables[b.parts[0].first].views[b.parts[0].second].view.height,
                   where, "a blend's parts differ in size");
      const uint64_t size = Get<uint64_t>(data, &pos, where, "blend weights size");
      HOVS_REQUIRE(size == uint64_t(vw.width) * vw.height && size <= data.size() - pos, where,
                   "truncated or damaged blend weights");
      b.weights.emplace_back(data.begin() + static_cast<long>(pos), data.begin() + static_cast<long>(pos + size));
      pos += size;
    }
  }
  HOVS_REQUIRE(pos == data.size(), where, data.size() - pos, " bytes after the last table");
  std::vector<bool> blend_used(m.blends.size(), false);
  for (const auto& [u, v] : m.order) {
    if (u == -1) {
      HOVS_REQUIRE(v >= 0 && v < int(m.blends.size()) && !blend_used[v], where,
                   "the header's view order does not match the blends");
      blend_used[v] = true;
      continue;
    }
    use(u, v);
  }
  for (const auto& t : used)
    for (const bool b : t) HOVS_REQUIRE(b, where, "a table's view is missing from the header's order");
  return m;
}

RigRemapper::RigRemapper(const RigMapping& mapping) : mapping_(mapping) {
  for (const auto& t : mapping_.tables) remappers_.push_back(std::make_unique<Remapper>(t));
  parts_.resize(mapping_.blends.size());
  for (auto& p : parts_) p.resize(2);
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
    if (mapping_.order[k].first >= 0) jobs[mapping_.order[k].first].outputs[mapping_.order[k].second] = &(*outputs)[k];
  for (size_t b = 0; b < mapping_.blends.size(); ++b)
    for (int p = 0; p < 2; ++p)
      jobs[mapping_.blends[b].parts[p].first].outputs[mapping_.blends[b].parts[p].second] = &parts_[b][p];
  RunRemappers(jobs, interp);
  for (size_t k = 0; k < mapping_.order.size(); ++k) {
    if (mapping_.order[k].first >= 0) continue;
    const int b = mapping_.order[k].second;
    const Image8 &p0 = parts_[b][0], &p1 = parts_[b][1];
    const uint8_t *w0 = mapping_.blends[b].weights[0].data(), *w1 = mapping_.blends[b].weights[1].data();
    Image8& o = (*outputs)[k];
    o.width = p0.width, o.height = p0.height, o.channels = p0.channels;
    o.data.resize(p0.data.size());
    const int C = p0.channels;
    tbb::parallel_for(0, o.height, [&](int y) {
      for (int x = 0; x < o.width; ++x) {
        const size_t i = size_t(y) * o.width + x;
        for (int c = 0; c < C; ++c)
          o.data[i * C + c] =
              static_cast<uint8_t>((p0.data[i * C + c] * w0[i] + p1.data[i * C + c] * w1[i] + 127) / 255);
      }
    });
  }
}

}  // namespace hovs::unwrap
