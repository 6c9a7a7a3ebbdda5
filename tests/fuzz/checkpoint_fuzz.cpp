// libFuzzer harness: the training checkpoint reader (DirectoryCheckpointer::load(),
// framework/include/mgrl/learning/checkpoint_store.hpp). The input is a checkpoint's files (state.json
// first), loaded as they are and resealed. A bad checkpoint is logged and ignored, never
// thrown.
#include "bundle_fuzz_support.hpp"
#include "mgrl/learning/checkpoint_store.hpp"

namespace {
constexpr std::size_t kVertices = 3;
const mgrl::fuzz::Scratch& scratch() {
  static const mgrl::fuzz::Scratch s;
  return s;
}
void load(const std::vector<mgrl::fuzz::File>& files) {
  const std::filesystem::path dir = scratch().fresh("checkpoint");
  mgrl::fuzz::writeFiles(dir, files);
  mgrl::fuzz::guarded("checkpoint", [&] {
    mgrl::DirectoryCheckpointer checkpoints(dir, "fuzz", mgrl::fuzz::smallModel(), kVertices, [](const std::string&) {});
    mgrl::QTable table(mgrl::fuzz::smallModel(), kVertices);
    (void)checkpoints.load(table);
  });
}
}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  mgrl::fuzz::maybeWriteSeed(scratch(), "state.json", [](const std::filesystem::path& dir) {
    mgrl::DirectoryCheckpointer checkpoints(dir, "fuzz", mgrl::fuzz::smallModel(), kVertices, {});
    checkpoints.save({{"updates", 12345}, {"rng", {1, 2, 3, 4}}, {"alpha", 0.5}},
                     mgrl::QTable(mgrl::fuzz::smallModel(), kVertices));
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<mgrl::fuzz::File> files = mgrl::fuzz::splitFiles(mgrl::fuzz::text(data, size), "state.json");
  load(files);
  if (mgrl::fuzz::reseal(files)) load(files);
  return 0;
}
