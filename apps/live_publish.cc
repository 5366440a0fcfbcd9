#include "apps/live_publish.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "apps/commands.h"
#include "core/error.h"

namespace hovs::apps {

std::optional<stream::DdsOptions> PublishCliOptions::Resolve() const {
  if (!publish) {
    HOVS_REQUIRE(domain < 0 && interface.empty() && peers.empty() && wait_subscribers == 0 && prefix == "hovs",
                 "--domain", "the DDS options need --publish");
    return std::nullopt;
  }
  stream::DdsOptions d;
  d.domain = domain;
  if (d.domain < 0) {
    const char* env = std::getenv("ROS_DOMAIN_ID");
    d.domain = 0;
    if (env && *env) {
      char* end = nullptr;
      const long v = std::strtol(env, &end, 10);
      HOVS_REQUIRE(*end == 0 && v >= 0 && v <= 232, "ROS_DOMAIN_ID", "'", env, "' is not a DDS domain id (0 .. 232)");
      d.domain = static_cast<int>(v);
    }
  }
  d.interface = interface, d.peers = peers;
  d.Check("--domain");
  stream::CheckRosNamespace(prefix, "--topic-prefix");
  return d;
}

void AddPublishOptions(CLI::App* sub, PublishCliOptions* o) {
  sub->add_flag("--publish", o->publish,
                "publish the views on DDS as ROS 2 topics /PREFIX/VIEW/image_raw and camera_info (Cyclone DDS)");
  AddBounded(sub, "--domain", &o->domain, "DDS domain id 0..232 (default: $ROS_DOMAIN_ID, else 0)", -1, 1e6);
  sub->add_option("--dds-interface", o->interface, "network interface (name or address) DDS uses, e.g. lo");
  sub->add_option("--dds-peer", o->peers, "unicast discovery peer (repeatable; turns multicast off), e.g. 127.0.0.1");
  sub->add_option("--topic-prefix", o->prefix, "ROS 2 namespace of the topics")->capture_default_str();
  AddBounded(sub, "--wait-subscribers", &o->wait_subscribers,
             "wait up to this many seconds for a subscriber on every image topic before the first frame", 0, 3600);
}

std::unique_ptr<stream::Publisher> OpenPublisher(const PublishCliOptions& o,
                                                 const std::optional<stream::DdsOptions>& dds,
                                                 const std::vector<unwrap::ViewSpec>& views) {
  if (!dds) return nullptr;
  auto pub = std::make_unique<stream::Publisher>(*dds, stream::TopicsOfViews(views, o.prefix, false));
  if (o.wait_subscribers > 0) {
    HOVS_REQUIRE(pub->WaitForSubscribers(1, o.wait_subscribers), "--wait-subscribers",
                 "no subscriber on every image topic within ", o.wait_subscribers, " s");
    // A camera's subscriber reads its CameraInfo too, and discovery may match that reader a little later than the
    // image's: give it up to 2 s so the first frame's CameraInfo is not lost, without requiring one.
    pub->WaitForSubscribers(1, std::min(2.0, o.wait_subscribers), /*camera_info=*/true);
  }
  return pub;
}

}  // namespace hovs::apps
