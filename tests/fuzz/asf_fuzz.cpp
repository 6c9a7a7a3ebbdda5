// libFuzzer harness: the ASF reader (framework/include/mgrl/motion/asf_amc.hpp). The input is an ASF,
// optionally followed by `\n@@file x.amc\n` and an AMC to load with it through
// loadMotion() (units, standing height).
#include "fuzz_support.hpp"
#include "mgrl/motion/asf_amc.hpp"
#include "mgrl/motion/motion_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const mgrl::fuzz::Scratch scratch;
  const std::vector<mgrl::fuzz::File> files = mgrl::fuzz::splitFiles(mgrl::fuzz::text(data, size), "fuzz.asf");
  mgrl::fuzz::guarded("asf", [&] { (void)mgrl::parseAsf(files.front().bytes, "fuzz.asf"); });
  if (files.size() < 2) return 0;
  mgrl::fuzz::writeFiles(scratch.path(), {{"fuzz.asf", files[0].bytes}, {"fuzz.amc", files[1].bytes}});
  mgrl::fuzz::guarded("asf+amc", [&] {
    mgrl::LoadOptions options;
    options.fps = 30;
    options.asf = scratch.path() / "fuzz.asf";
    options.warn = [](const std::string&) {};
    (void)mgrl::loadMotion(scratch.path() / "fuzz.amc", options);
  });
  return 0;
}
