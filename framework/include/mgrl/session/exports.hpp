#pragma once
/// \file
/// A world run's exports (`mgrl simulate --bvh-out, --gltf-out, --events-out`; a library
/// call for other front ends): one BVH and/or binary glTF per avatar and the hit events,
/// each output folder checked and its scratch folder made before anything is simulated,
/// then written and swapped in whole with its manifest; a failed run leaves nothing behind.
/// Messages name the settings as the caller calls them (ExportFields: the command line's
/// options by default, Python's keywords from Session.simulate).
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "mgrl/core/bundle.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "mgrl/session/session.hpp"

namespace mgrl {

// A scratch folder for output, removed again with everything in it. If the output folder
// around it was made for this run, that goes too unless the run keeps its results
// (keep()): what a failed run leaves behind is nothing.
class ScratchDirectory {
 public:
  ScratchDirectory(std::filesystem::path path, std::filesystem::path created)
      : path_(std::move(path)), created_(std::move(created)) {}
  ~ScratchDirectory() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
    if (!created_.empty()) std::filesystem::remove_all(created_, ec);
  }
  ScratchDirectory(const ScratchDirectory&) = delete;
  ScratchDirectory& operator=(const ScratchDirectory&) = delete;
  const std::filesystem::path& path() const { return path_; }
  void keep() { created_.clear(); }

 private:
  std::filesystem::path path_;
  std::filesystem::path created_;  ///< the outermost folder this run created ("" none)
};

// Where the run's outputs go: checked, and their scratch folders made, before anything is
// simulated (and removed again if the run fails).
// One output folder (--bvh-out, --gltf-out, or both when they name the same folder): one
// unit, written beside it and swapped in whole with its manifest.
struct OutputFolder {
  std::string option;         ///< "--bvh-out", "--gltf-out" or "--bvh-out and --gltf-out" (as ExportFields name them)
  std::filesystem::path dir;  ///< as given
  bool bvh = false, gltf = false, events = false;
  std::unique_ptr<ScratchDirectory> created;
  std::unique_ptr<BundleWriter> bundle;
};
struct Outputs {
  std::vector<OutputFolder> folders;
  std::unique_ptr<ScratchDirectory> eventsScratch;  ///< --events-out outside every output folder
};

/// What messages call the export settings.
struct ExportFields {
  std::string_view bvhOut = "--bvh-out", gltfOut = "--gltf-out", eventsOut = "--events-out";
  std::string_view avatars = "--avatars", seconds = "--seconds";
};

/// What to export and the run's facts for the manifests.
struct ExportRequest {
  std::filesystem::path bvhOut;     ///< one BVH per avatar here ("" none)
  std::filesystem::path gltfOut;    ///< one binary glTF (.glb) per avatar here ("" none)
  std::filesystem::path eventsOut;  ///< hits as JSON lines ("" none)
  long long avatars = 2;
  double seconds = 10;  ///< simulated time
  std::string controller = "policy";
  std::uint64_t seed = 1;
  ExportFields fields;
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
Outputs prepareOutputs(const ExportRequest& options, const Scenario& scenario);

/// Writes the run's outputs into the bundles' temporaries and the scratch folder, then puts
/// them in place: each output folder whole (with the events if they belong to it), then the
/// events. Returns the motion files written.
WrittenFiles writeOutputs(Outputs& out, const ExportRequest& options, const Session& session, const World& world,
                          std::size_t frames);

}  // namespace mgrl
