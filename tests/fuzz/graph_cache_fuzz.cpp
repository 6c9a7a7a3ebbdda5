// libFuzzer harness: the graph cache reader (loadGraphBundle(), framework/include/mgrl/graph/graph_cache.hpp).
// The input is a bundle's files (manifest.json first, see splitFiles()); each is loaded as
// it is and resealed (fuzz_support.hpp: reseal()), so the checks behind the hashes run too.
// loadGraphBundle() reports a bad bundle in its status and never throws. The motion the
// bundle may keep (version 4) is read too.
#include "bundle_fuzz_support.hpp"
#include "mgrl/graph/graph_cache.hpp"

namespace {
const mgrl::fuzz::Scratch& scratch() {
  static const mgrl::fuzz::Scratch s;
  return s;
}
void load(const std::vector<mgrl::fuzz::File>& files) {
  const std::filesystem::path dir = scratch().fresh("graph");
  mgrl::fuzz::writeFiles(dir, files);
  mgrl::fuzz::guarded("graph cache", [&] { (void)mgrl::loadGraphBundle(dir, "fuzz", true); });
}
}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  mgrl::fuzz::maybeWriteSeed(scratch(), "manifest.json", [](const std::filesystem::path& dir) {
    mgrl::saveGraphBundle(dir, mgrl::fuzz::smallModel(), {{"key", "fuzz"}}, mgrl::fuzz::smallClips());
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<mgrl::fuzz::File> files = mgrl::fuzz::splitFiles(mgrl::fuzz::text(data, size), "manifest.json");
  load(files);
  if (mgrl::fuzz::reseal(files)) load(files);
  return 0;
}
