// test-fault: a test-only engine that fails on demand, so the harness's tests can show that a
// job whose adapter aborts or hangs becomes a `crashed` or `timeout` row and the suite goes on.
// It is not a physics engine: `physbench list` does not show it and a run without `-e test-fault`
// never schedules it (docs/engines.md, "Test-only engine").
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <thread>

#include "physbench/registry.h"

namespace physbench {

namespace {

class FaultEngine final : public Engine {
 public:
  explicit FaultEngine(std::string variant) : variant_(std::move(variant)) {}
  void load(const Scene&) override {
    // abort-later: runs in the first process of a job and aborts in every later one (a timing
    // round), as an engine that crashes now and then would; the processes share a marker file
    // named by PHYSBENCH_TEST_FAULT_MARKER (without it the variant never aborts)
    if (variant_ == "abort-later") {
      const char* marker = std::getenv("PHYSBENCH_TEST_FAULT_MARKER");
      if (!marker) return;
      if (std::ifstream(marker).good()) std::abort();
      std::ofstream(marker) << "ran once\n";
    }
  }
  void step() override {
    // abort: the adapter dies by SIGABRT in its first step, as a failed assertion would
    if (variant_ == "abort") std::abort();
    // hang: the first step never returns, as a solver stuck in a loop would not
    if (variant_ == "hang")
      for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
  }
  SampledState body_state(int) const override { return {}; }
  void apply_impulse(int, const Vec3&, const Vec3&) override {}

 private:
  std::string variant_;
};

}  // namespace

EngineInfo fault_engine_info() {
  EngineInfo info;
  info.name = "test-fault";
  info.variants = {"abort", "hang", "abort-later"};
  info.version = "test only";
  info.test_only = true;
  info.unsupported = [](const Scene&, const std::string&) -> std::optional<std::string> {
    return std::nullopt;
  };
  info.create = [](const std::string& variant) -> std::unique_ptr<Engine> {
    return std::make_unique<FaultEngine>(variant);
  };
  info.settings = [](const std::string& variant) {
    return std::vector<Setting>{{"failure", variant,
                                 "test-only engine: fails on purpose, so that the harness's "
                                 "handling of a crashed or hung adapter can be tested"}};
  };
  return info;
}

}  // namespace physbench
