#pragma once
// The bundle harnesses' common part: a small synthetic graph to load tables against, and
// the seed writer (MGRL_FUZZ_WRITE_SEED=FILE makes a harness write one seed input, a bundle
// saved by the project's own writer, and exit).
#include <algorithm>
#include <fstream>

#include "mgrl/core/files.hpp"

#include "fuzz_support.hpp"
#include "synthetic_model.hpp"

namespace mgrl::fuzz {

inline const StateActionModel& smallModel() {
  static const StateActionModel model = [] {
    SyntheticModelSpec spec;
    spec.states = 6;
    spec.actions = 14;
    return makeSyntheticModel(spec);
  }();
  return model;
}

/// The files of the bundle at `dir`, `first` first, as one input (joinFiles()).
inline std::string bundleInput(const std::filesystem::path& dir, const std::string& first) {
  std::vector<File> files = {{first, mgrl::readFile(dir / first)}};
  std::vector<std::string> names;
  for (const auto& item : std::filesystem::directory_iterator(dir))
    if (item.path().filename() != first) names.push_back(item.path().filename().string());
  std::sort(names.begin(), names.end());
  for (const std::string& name : names) files.push_back({name, mgrl::readFile(dir / name)});
  return joinFiles(files);
}

/// If MGRL_FUZZ_WRITE_SEED is set: `save(dir)` writes a bundle into a scratch folder,
/// whose files go to that file as one input; then the process exits.
template <class Save>
void maybeWriteSeed(const Scratch& scratch, const std::string& first, Save&& save) {
  const char* out = std::getenv("MGRL_FUZZ_WRITE_SEED");
  if (!out || !*out) return;
  const std::filesystem::path dir = scratch.path() / "seed";
  save(dir);
  const std::string input = bundleInput(dir, first);
  std::ofstream(out, std::ios::binary).write(input.data(), static_cast<std::streamsize>(input.size()));
  std::exit(0);
}

}  // namespace mgrl::fuzz
