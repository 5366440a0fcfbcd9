// Publishing the article's six 1200 x 700 RGB views (15.1 MB a frame) over DDS on the loopback to a reader in
// another process, as `hovs live --publish` does: the writer thread's sustained rate, frames and MB per second
// (reliable writer, unicast discovery on lo; the reader takes every message as it arrives). Target: the article's
// 10 frames per second with room to spare.
#include <benchmark/benchmark.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include "stream/publisher.h"
#include "stream/subscriber.h"

namespace {

using namespace hovs;

stream::DdsOptions Loopback() {
  stream::DdsOptions o;
  o.domain = 77, o.interface = "lo", o.peers = {"127.0.0.1"};
  return o;
}

const char* kViews[6] = {"v0", "v1", "v2", "v3", "v4", "v5"};

[[noreturn]] void Reader() {
  std::vector<std::unique_ptr<stream::Subscriber>> subs;
  for (const char* v : kViews)
    subs.push_back(std::make_unique<stream::Subscriber>(Loopback(), "/hovs/" + std::string(v) + "/image_raw",
                                                        stream::MessageType::kImage, 4));
  for (;;)
    for (auto& s : subs) s->Take(0.001);
}

void BM_PublishArticleViewsLoopback(benchmark::State& state) {
  const pid_t child = fork();
  if (child == 0) Reader();
  {
    std::vector<unwrap::ViewSpec> specs(6);
    for (int k = 0; k < 6; ++k) specs[k].name = kViews[k], specs[k].type = ViewProjection::kCylindrical;  // images only
    stream::Publisher pub(Loopback(), stream::TopicsOfViews(specs, "hovs", false));
    if (!pub.WaitForSubscribers(1, 30)) state.SkipWithError("no reader matched within 30 s");
    stream::Bundle b;
    for (int k = 0; k < 6; ++k) b.images.push_back({1200, 700, 3, std::vector<uint8_t>(1200 * 700 * 3, uint8_t(k))});
    uint64_t n = 0;
    for (auto _ : state) {
      b.stamp_ns = ++n;
      pub.Offer(&b, true);
      pub.Flush(10);
      if (b.images.empty())
        for (int k = 0; k < 6; ++k) b.images.push_back({1200, 700, 3, std::vector<uint8_t>(1200 * 700 * 3)});
    }
    const auto s = pub.Stats();
    state.counters["fps"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["MB_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()) * 6 * 1200 * 700 * 3 / 1e6,
                                                    benchmark::Counter::kIsRate);
    state.counters["incomplete"] = static_cast<double>(s.incomplete);
  }
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
}
BENCHMARK(BM_PublishArticleViewsLoopback)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(5.0);

}  // namespace
