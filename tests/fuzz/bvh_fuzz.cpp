// libFuzzer harness: the BVH reader (framework/include/mgrl/motion/bvh.hpp) as every command meets it,
// through loadMotion(): parsing, units detected from the standing height, resampling to
// 30 fps.
#include "fuzz_support.hpp"
#include "mgrl/motion/motion_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const mgrl::fuzz::Scratch scratch;
  const std::filesystem::path file = scratch.path() / "fuzz.bvh";
  mgrl::fuzz::writeFiles(scratch.path(), {{"fuzz.bvh", std::string(mgrl::fuzz::text(data, size))}});
  mgrl::fuzz::guarded("bvh", [&] {
    mgrl::LoadOptions options;
    options.fps = 30;
    options.warn = [](const std::string&) {};
    (void)mgrl::loadMotion(file, options);
  });
  return 0;
}
