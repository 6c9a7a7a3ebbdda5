// libFuzzer harness: the policy bundle reader (loadPolicyBundle(),
// framework/learning/policy_bundle.hpp) against a small synthetic graph. The input is a
// bundle's files (manifest.json first), loaded as they are and resealed.
#include "bundle_fuzz_support.hpp"
#include "mgrl/learning/policy_bundle.hpp"

namespace {
const mgrl::fuzz::Scratch& scratch() {
  static const mgrl::fuzz::Scratch s;
  return s;
}
void load(const std::vector<mgrl::fuzz::File>& files) {
  const std::filesystem::path dir = scratch().fresh("policy");
  mgrl::fuzz::writeFiles(dir, files);
  mgrl::fuzz::guarded("policy bundle", [&] { (void)mgrl::loadPolicyBundle(dir, mgrl::fuzz::smallModel(), "fuzz"); });
}
}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  mgrl::fuzz::maybeWriteSeed(scratch(), "manifest.json", [](const std::filesystem::path& dir) {
    const mgrl::StateActionModel& model = mgrl::fuzz::smallModel();
    mgrl::PolicyBundle bundle;
    bundle.graphKey = "fuzz";
    bundle.provenance = {{"scenario", "fuzz.yaml"}};
    mgrl::PolicyBehavior behavior;
    behavior.key = "k";
    behavior.record = {{"learner", "q_learning"}};
    behavior.table = mgrl::QTable(model, 3);
    behavior.vertices = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    bundle.behaviors.emplace("hit", std::move(behavior));
    mgrl::savePolicyBundle(dir, bundle);
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<mgrl::fuzz::File> files = mgrl::fuzz::splitFiles(mgrl::fuzz::text(data, size), "manifest.json");
  load(files);
  if (mgrl::fuzz::reseal(files)) load(files);
  return 0;
}
