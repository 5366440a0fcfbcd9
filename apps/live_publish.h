// hovs live --publish: the views (and later the depth) of every frame on DDS with ROS 2's conventions
// (stream/publisher.h), the options that configure it, and its figures for live.json.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "stream/publisher.h"
#include "unwrap/layout.h"

namespace hovs::apps {

struct PublishCliOptions {
  bool publish = false;
  int domain = -1;  // -1: $ROS_DOMAIN_ID, else 0
  std::string interface, prefix = "hovs";
  std::vector<std::string> peers;
  double wait_subscribers = 0;  // s to wait for a subscriber on every topic before the first frame
  // The DDS options (nullopt without --publish), checked: a domain out of range (or a bad $ROS_DOMAIN_ID), an
  // interface the machine lacks, DDS options without --publish are refused naming the option.
  std::optional<stream::DdsOptions> Resolve() const;
};

void AddPublishOptions(CLI::App* sub, PublishCliOptions* o);

// The publisher of the views (nullptr without --publish); waits for subscribers as asked. Throws naming
// the option Cyclone or the machine refuses.
std::unique_ptr<stream::Publisher> OpenPublisher(const PublishCliOptions& o,
                                                 const std::optional<stream::DdsOptions>& dds,
                                                 const std::vector<unwrap::ViewSpec>& views);

}  // namespace hovs::apps
