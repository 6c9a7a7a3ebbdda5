#pragma once
// The bundle harnesses' common part: a small synthetic graph to load tables against, and
// the seed writer (MGRL_FUZZ_WRITE_SEED=FILE makes a harness write one seed input, a bundle
// saved by the project's own writer, and exit).
#include <algorithm>
#include <fstream>

#include <memory>
#include <string>

#include "mgrl/core/files.hpp"
#include "mgrl/motion/motion_database.hpp"

#include "fuzz_support.hpp"
#include "synthetic_model.hpp"

namespace mgrl::fuzz {

inline const StateActionModel& smallModel() {
  static const StateActionModel model = [] {
    SyntheticModelSpec spec;
    spec.states = 6;
    spec.actions = 14;
    StateActionModel m = makeSyntheticModel(spec);
    // smallClips()'s one joint, playing every role, so the joint arrays are fuzzed too.
    m.jointNames = {"Hips"};
    m.roleJoint.assign(roleNames().size(), 0);
    for (std::uint32_t f = 0; f < m.framesTotal; ++f) {
      m.sourceJoint.insert(m.sourceJoint.end(), {0.0f, 0.9f, 0.01f * static_cast<float>(f)});
      m.sourceJointSpeed.push_back(0.3f);
    }
    return m;
  }();
  return model;
}

/// Clips for smallModel()'s frames, on a one-joint skeleton (position and rotation
/// channels, an end site: a seed under the fuzzer's 64 KB), so the graph seed carries a
/// "motion" member to mutate.
inline std::vector<Clip> smallClips() {
  std::vector<Joint> joints(1);
  joints[0].name = "Hips";
  joints[0].channels = {{Channel::Kind::Position, Axis::X}, {Channel::Kind::Position, Axis::Y},
                        {Channel::Kind::Position, Axis::Z}, {Channel::Kind::Rotation, Axis::Z},
                        {Channel::Kind::Rotation, Axis::X}, {Channel::Kind::Rotation, Axis::Y}};
  joints[0].endSite = Eigen::Vector3d(0, 0.5, 0);
  const auto skeleton = std::make_shared<const Skeleton>(std::move(joints));
  const StateActionModel& m = smallModel();
  std::vector<Clip> clips;
  for (std::size_t c = 0; c + 1 < m.clipOffset.size(); ++c) {
    const std::size_t frames = m.clipOffset[c + 1] - m.clipOffset[c];
    std::vector<Eigen::Quaterniond> rotations;
    std::vector<Eigen::Vector3d> translations;
    for (std::size_t f = 0; f < frames; ++f) {
      rotations.emplace_back(Eigen::AngleAxisd(0.1 * static_cast<double>(f + c), Eigen::Vector3d::UnitY()));
      translations.emplace_back(0.01 * static_cast<double>(f), 0.9, 0);
    }
    clips.push_back(Clip{"clip" + std::to_string(c) + ".bvh", {}, Motion(skeleton, m.frameTime, rotations, translations), {}});
  }
  return clips;
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
