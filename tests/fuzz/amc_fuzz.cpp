// libFuzzer harness: the AMC reader (framework/include/mgrl/motion/asf_amc.hpp) for a fixed skeleton
// (amc_skeleton.asf, cut down from CMU 02.asf into the fuzz build's seeds/ folder by
// make_corpus.py, which scripts/fuzz.sh runs first), then units and resampling as
// loadMotion() does them.
#include "fuzz_support.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/motion/asf_amc.hpp"
#include "mgrl/motion/motion_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const mgrl::fuzz::Scratch scratch;
  static const std::string asfText = mgrl::readFile(MGRL_FUZZ_SEEDS "/amc_skeleton.asf");
  static const mgrl::AsfSkeleton asf = mgrl::parseAsf(asfText, "amc_skeleton.asf");
  mgrl::fuzz::guarded("amc", [&] { (void)mgrl::parseAmc(mgrl::fuzz::text(data, size), "fuzz.amc", asf); });
  mgrl::fuzz::writeFiles(scratch.path(), {{"fuzz.asf", asfText}, {"fuzz.amc", std::string(mgrl::fuzz::text(data, size))}});
  mgrl::fuzz::guarded("amc load", [&] {
    mgrl::LoadOptions options;
    options.fps = 30;
    options.asf = scratch.path() / "fuzz.asf";
    options.warn = [](const std::string&) {};
    (void)mgrl::loadMotion(scratch.path() / "fuzz.amc", options);
  });
  return 0;
}
