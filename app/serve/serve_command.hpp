#pragma once
/// \file
/// `mgrl serve` (docs/viewer-protocol.md): loads the scenario's graph and policy once,
/// then serves the viewer until Ctrl-C.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "serve/viewer.hpp"

namespace mgrl::serve {

struct ServeCommandOptions : ServeOptions {
  std::string host = "127.0.0.1";
  long long port = 8080;
  std::filesystem::path web;  ///< "" MGRL_WEB, else the repository's web/
  bool open = false;          ///< start the desktop's browser on the URL
  std::vector<std::string> allowOrigins;  ///< --allow-origin: pages of these origins may connect too
  /// Told the URL once the server listens (stdout).
  std::function<void(const std::string&)> announce;
};

/// The viewer's folder: `web` if given, else MGRL_WEB, else the installed page beside the
/// program (PREFIX/share/mgrl/web for PREFIX/bin/mgrl), else the source tree's web/.
std::filesystem::path webDirectory(const std::filesystem::path& web);

/// Serves until SIGINT or SIGTERM. Throws mgrl::Error before serving for a bad option, a
/// missing web folder, a port in use or an unusable policy bundle given with --policy.
void runServe(const ServeCommandOptions& options);

}  // namespace mgrl::serve
