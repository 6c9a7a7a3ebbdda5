#pragma once
/// \file
/// `mgrl simulate`'s output folders (--bvh-out, --gltf-out, --events-out): checked and
/// their scratch folders made before anything is simulated, then written and swapped in
/// whole, each folder one unit with its manifest; a failed run leaves nothing behind.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "learn_commands.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "mgrl/session/session.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;

// A scratch folder for output, removed again with everything in it. If the output folder
// around it was made for this run, that goes too unless the run keeps its results
// (keep()): what a failed run leaves behind is nothing.
class ScratchDirectory {
 public:
  ScratchDirectory(fs::path path, fs::path created) : path_(std::move(path)), created_(std::move(created)) {}
  ~ScratchDirectory() {
    std::error_code ec;
    fs::remove_all(path_, ec);
    if (!created_.empty()) fs::remove_all(created_, ec);
  }
  ScratchDirectory(const ScratchDirectory&) = delete;
  ScratchDirectory& operator=(const ScratchDirectory&) = delete;
  const fs::path& path() const { return path_; }
  void keep() { created_.clear(); }

 private:
  fs::path path_;
  fs::path created_;  ///< the outermost folder this run created ("" none)
};

// Where the run's outputs go: checked, and their scratch folders made, before anything is
// simulated (and removed again if the run fails).
// One output folder (--bvh-out, --gltf-out, or both when they name the same folder): one
// unit, written beside it and swapped in whole with its manifest.
struct OutputFolder {
  std::string option;  ///< "--bvh-out", "--gltf-out" or "--bvh-out and --gltf-out"
  fs::path dir;        ///< as given
  bool bvh = false, gltf = false, events = false;
  std::unique_ptr<ScratchDirectory> created;
  std::unique_ptr<BundleWriter> bundle;
};
struct Outputs {
  std::vector<OutputFolder> folders;
  std::unique_ptr<ScratchDirectory> eventsScratch;  ///< --events-out outside every output folder
};

struct WrittenFiles {
  std::vector<std::string> bvh, gltf;
  std::string bvhFolder, gltfFolder;
};

/// The most memory a recording for export may take (bytes).
inline constexpr double kMaxRecordingBytes = 4e9;
/// Memory to record `avatarFrames` poses of `joints` joints for export (bytes).
double recordingBytes(double avatarFrames, double joints);

/// Checks the output options against what is on disk and makes each folder's scratch
/// space (removed again if the run fails). Throws mgrl::Error naming the option.
Outputs prepareOutputs(const SimulateOptions& options, const Scenario& scenario);

/// Writes the run's outputs into the bundles' temporaries and the scratch folder, then puts
/// them in place: each output folder whole (with the events if they belong to it), then the
/// events. Returns the motion files written.
WrittenFiles writeOutputs(Outputs& out, const SimulateOptions& options, const Session& session, const World& world,
                          std::size_t frames);

}  // namespace mgrl::app
