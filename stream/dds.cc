#include "stream/dds.h"

#include <arpa/inet.h>
#include <dds/dds.h>
#include <ifaddrs.h>
#include <net/if.h>

#include <cctype>
#include <cmath>
#include <map>
#include <mutex>
#include <set>

#include "core/error.h"

namespace hovs::stream {
namespace {

bool PlainName(const std::string& s) {
  if (s.empty()) return false;
  for (const char c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != ':' && c != '_' && c != '-') return false;
  return true;
}

bool IsAddress(const std::string& s) {
  unsigned char buf[16];
  return inet_pton(AF_INET, s.c_str(), buf) == 1 || inet_pton(AF_INET6, s.c_str(), buf) == 1;
}

// The machine's interfaces by name, and their addresses.
std::map<std::string, std::set<std::string>> Interfaces() {
  std::map<std::string, std::set<std::string>> out;
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return out;
  for (ifaddrs* a = list; a; a = a->ifa_next) {
    auto& addrs = out[a->ifa_name];
    if (!a->ifa_addr) continue;
    char text[INET6_ADDRSTRLEN] = {0};
    if (a->ifa_addr->sa_family == AF_INET)
      inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(a->ifa_addr)->sin_addr, text, sizeof text);
    else if (a->ifa_addr->sa_family == AF_INET6)
      inet_ntop(AF_INET6, &reinterpret_cast<sockaddr_in6*>(a->ifa_addr)->sin6_addr, text, sizeof text);
    if (text[0]) addrs.insert(text);
  }
  freeifaddrs(list);
  return out;
}

// One Cyclone domain per id and process, shared by the participants that ask for the same configuration.
struct DomainEntry {
  dds_entity_t handle = 0;
  std::string xml;
  int users = 0;
};
std::mutex domains_mutex;
std::map<int, DomainEntry> domains;

std::string DomainWhere(const DdsOptions& o) { return "DDS domain " + std::to_string(o.domain); }

}  // namespace

void DdsOptions::Check(const std::string& where) const {
  HOVS_REQUIRE(domain >= 0 && domain <= 232, where.empty() ? "--domain" : where,
               "the DDS domain id must be 0 .. 232, not ", domain);
  HOVS_REQUIRE(std::isfinite(max_blocking_s) && max_blocking_s >= 0 && max_blocking_s <= 60, where,
               "the writers' blocking time must be 0 .. 60 s, not ", max_blocking_s);
  HOVS_REQUIRE(history >= 0 && history <= 10000, where, "the writers' history must be 0 (all) .. 10000 samples, not ",
               history);
  if (!interface.empty()) {
    HOVS_REQUIRE(PlainName(interface), "--dds-interface", "'", interface, "' is not an interface name or address");
    const auto ifs = Interfaces();
    bool found = ifs.count(interface) > 0;
    for (const auto& [name, addrs] : ifs) found = found || addrs.count(interface) > 0;
    std::string names;
    for (const auto& [name, addrs] : ifs) names += (names.empty() ? "" : ", ") + name;
    HOVS_REQUIRE(found, "--dds-interface", "this machine has no interface '", interface, "' (it has: ", names, ")");
  }
  for (const auto& p : peers) HOVS_REQUIRE(PlainName(p), "--dds-peer", "'", p, "' is not an address or host name");
}

std::string DdsConfigXml(const DdsOptions& o) {
  if (o.interface.empty() && o.peers.empty()) return "";
  std::string xml = "<CycloneDDS><Domain id=\"any\"><General>";
  if (!o.interface.empty())
    xml += std::string("<Interfaces><NetworkInterface ") + (IsAddress(o.interface) ? "address" : "name") + "=\"" +
           o.interface + "\"/></Interfaces>";
  if (!o.peers.empty()) xml += "<AllowMulticast>false</AllowMulticast>";
  xml += "</General>";
  // Frames of several MB arrive as bursts of fragments: a receive buffer as large as the kernel allows (Cyclone
  // asks for this much and takes less where net.core.rmem_max is lower) keeps retransmissions rare.
  xml += "<Internal><SocketReceiveBufferSize max=\"32MB\"/></Internal>";
  if (!o.peers.empty()) {
    // Unicast discovery: every participant takes a port index of its own, and the peers are probed at the first
    // indices' ports.
    xml +=
        "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20</MaxAutoParticipantIndex>"
        "<Peers>";
    for (const auto& p : o.peers) xml += "<Peer address=\"" + p + "\"/>";
    xml += "</Peers></Discovery>";
  }
  xml += "</Domain></CycloneDDS>";
  return xml;
}

Participant::Participant(const DdsOptions& options) : options_(options) {
  options_.Check("--domain");
  const std::string xml = DdsConfigXml(options_);
  {
    std::lock_guard<std::mutex> lock(domains_mutex);
    auto it = domains.find(options_.domain);
    if (it == domains.end()) {
      DomainEntry e;
      e.xml = xml;
      if (!xml.empty()) {
        e.handle = dds_create_domain(static_cast<dds_domainid_t>(options_.domain), xml.c_str());
        HOVS_REQUIRE(e.handle > 0, DomainWhere(options_), "Cyclone DDS refused the configuration (",
                     dds_strretcode(e.handle), "): ", xml);
      }
      it = domains.emplace(options_.domain, e).first;
    } else {
      HOVS_REQUIRE(it->second.xml == xml, DomainWhere(options_),
                   "already open in this process with another interface or peers");
    }
    ++it->second.users;
  }
  handle_ = dds_create_participant(static_cast<dds_domainid_t>(options_.domain), nullptr, nullptr);
  if (handle_ <= 0) {
    const dds_return_t rc = handle_;
    handle_ = 0;
    std::lock_guard<std::mutex> lock(domains_mutex);
    auto it = domains.find(options_.domain);
    if (--it->second.users == 0) {
      if (it->second.handle > 0) dds_delete(it->second.handle);
      domains.erase(it);
    }
    throw Error(DomainWhere(options_), std::string("Cyclone DDS could not create a participant: ") +
                                           dds_strretcode(rc) +
                                           " (CYCLONEDDS_URI, --dds-interface and --dds-peer configure it)");
  }
}

Participant::~Participant() {
  if (handle_ > 0) dds_delete(handle_);
  std::lock_guard<std::mutex> lock(domains_mutex);
  auto it = domains.find(options_.domain);
  if (it != domains.end() && --it->second.users == 0) {
    if (it->second.handle > 0) dds_delete(it->second.handle);
    domains.erase(it);
  }
}

std::string RosTopic(const std::string& prefix, const std::vector<std::string>& parts) {
  std::string out;
  auto add = [&](const std::string& token) {
    for (size_t start = 0; start <= token.size();) {
      size_t end = token.find('/', start);
      if (end == std::string::npos) end = token.size();
      std::string t = token.substr(start, end - start);
      start = end + 1;
      if (t.empty()) continue;
      for (char& c : t)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
      if (std::isdigit(static_cast<unsigned char>(t[0]))) t = "_" + t;
      out += "/" + t;
    }
  };
  add(prefix);
  for (const auto& p : parts) add(p);
  return out.empty() ? "/" : out;
}

void CheckRosNamespace(const std::string& ns, const std::string& where) {
  HOVS_REQUIRE(!ns.empty() && ns != "/", where, "the namespace is empty");
  HOVS_REQUIRE(ns.size() <= 200, where, "the namespace has ", ns.size(), " characters (at most 200)");
  HOVS_REQUIRE(ns.back() != '/', where, "'", ns, "' ends with '/'");
  HOVS_REQUIRE(ns.find("//") == std::string::npos, where, "'", ns, "' has an empty name between two '/'");
  HOVS_REQUIRE(ns.find("__") == std::string::npos, where, "'", ns, "' repeats '_' (ROS 2 names may not hold \"__\")");
  for (size_t i = 0; i < ns.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(ns[i]);
    HOVS_REQUIRE(std::isalnum(c) || c == '_' || c == '/', where, "'", ns, "' holds the character '", ns.substr(i, 1),
                 "' (ROS 2 names take letters, digits, '_' and '/')");
    HOVS_REQUIRE(!std::isdigit(c) || (i > 0 && ns[i - 1] != '/'), where, "'", ns,
                 "': a name may not start with a digit");
  }
  HOVS_REQUIRE(!std::isdigit(static_cast<unsigned char>(ns[0])), where, "'", ns,
               "': a name may not start with a digit");
}

std::string DdsTopic(const std::string& ros_topic) {
  return "rt" + (ros_topic.empty() || ros_topic[0] != '/' ? "/" + ros_topic : ros_topic);
}

std::string RosTypeName(MessageType type) {
  switch (type) {
    case MessageType::kImage: return "sensor_msgs/msg/Image";
    case MessageType::kCameraInfo: return "sensor_msgs/msg/CameraInfo";
    case MessageType::kPointCloud2: return "sensor_msgs/msg/PointCloud2";
  }
  return "";
}

}  // namespace hovs::stream
