// libFuzzer harness: the policy bundle reader (loadPolicyBundle(),
// framework/include/mgrl/learning/policy_bundle.hpp) against a small synthetic graph, and a kd_tree
// rebuilt from a behaviour's saved tree arrays (KdTree::restored(), as eval and serve do).
// The input is a bundle's files (manifest.json first), loaded as they are and resealed.
#include "bundle_fuzz_support.hpp"
#include "discretizers/discretizers.hpp"
#include "mgrl/learning/policy_bundle.hpp"

namespace {
const mgrl::fuzz::Scratch& scratch() {
  static const mgrl::fuzz::Scratch s;
  return s;
}
// The scenario's tree a saved kd_tree behaviour is restored onto: 3 x 2 initial cells (3
// root boxes), so a bundle may carry roots and, from another start, start_cells.
const mgrl::Discretizer& scenarioTree() {
  static const std::unique_ptr<mgrl::Discretizer> tree = [] {
    mgrl::DiscretizerRegistry registry("discretizer");
    mgrl::discretizers::registerAll(registry);
    return registry.create(
        mgrl::ConfigNode::parse("{type: kd_tree, coordinates: polar, angle_cells: 3, distance_cells: 2, angle_min: -90, "
                                "angle_max: 90, distance_min: 0.5, distance_max: 2.5, max_depth: 10}",
                                "fuzz.yaml"),
        mgrl::fuzz::smallModel());
  }();
  return *tree;
}
void load(const std::vector<mgrl::fuzz::File>& files) {
  const std::filesystem::path dir = scratch().fresh("policy");
  mgrl::fuzz::writeFiles(dir, files);
  mgrl::fuzz::guarded("policy bundle", [&] {
    const mgrl::PolicyBundle bundle = mgrl::loadPolicyBundle(dir, mgrl::fuzz::smallModel(), "fuzz");
    for (const auto& [name, behavior] : bundle.behaviors)
      if (behavior.gridType == "kd_tree") (void)scenarioTree().restored(behavior.grid);
  });
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
    // A refined tree grown from other initial cells (5 x 3: start_cells and 15 roots).
    std::shared_ptr<const mgrl::Discretizer> tree = scenarioTree().withInitialCells({5, 3});
    tree = tree->refined({0, 7});
    mgrl::PolicyBehavior saved;
    saved.key = "t";
    saved.record = {{"learner", "adaptive_value_iteration"}};
    saved.table = mgrl::QTable(model, tree->vertexCount());
    for (std::size_t v = 0; v < tree->vertexCount(); ++v) {
      const Eigen::Vector3d p = tree->vertexPosition(v);
      saved.vertices.insert(saved.vertices.end(), {p.x(), p.y(), p.z()});
    }
    saved.gridType = "kd_tree";
    saved.grid = tree->structure();
    bundle.behaviors.emplace("tree", std::move(saved));
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
