#pragma once
/// \file
/// Where the motion capture lives: `--data DIR`, else the MGRL_DATA environment variable,
/// else the user's data folder (`$XDG_DATA_HOME/mgrl`, default `~/.local/share/mgrl`, where
/// scripts/fetch_data.sh downloads it) if it exists, else `../shared/mocap` next to the
/// repository root (DESIGN.md sec. 6).

#include <filesystem>

namespace mgrl {

/// The data folder. `explicitDir` (from --data) wins when not empty. Does not check that
/// the folder exists.
std::filesystem::path dataDirectory(const std::filesystem::path& explicitDir = {});

/// `$XDG_DATA_HOME/mgrl`, else `$HOME/.local/share/mgrl`; "" without either variable.
std::filesystem::path userDataDirectory();

/// The data folder the last scenario was read with (the scenario reader records it), else
/// dataDirectory(). For plug-ins that read capture of their own when they bind (the facing
/// term's `prefer: bouts`), which see neither the command line nor the scenario. One per
/// process: sessions on two data folders at once would share the last one.
std::filesystem::path scenarioDataDirectory();
void recordScenarioDataDirectory(const std::filesystem::path& dir);

}  // namespace mgrl
