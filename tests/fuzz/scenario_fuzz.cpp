// libFuzzer harness: the YAML scenario reader (framework/include/mgrl/scenario/scenario.hpp), with the
// real data folder so motion paths resolve (MGRL_FUZZ_DATA, default ../shared/mocap).
#include "fuzz_support.hpp"
#include "mgrl/scenario/scenario.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path dataDir = [] {
    const char* set = std::getenv("MGRL_FUZZ_DATA");
    return std::filesystem::path(set && *set ? set : MGRL_SOURCE_DIR "/../shared/mocap");
  }();
  mgrl::fuzz::guarded("scenario", [&] {
    (void)mgrl::parseScenario(mgrl::fuzz::text(data, size), MGRL_SOURCE_DIR "/scenarios/fuzz.yaml", dataDir);
  });
  return 0;
}
