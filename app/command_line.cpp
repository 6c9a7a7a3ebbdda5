// mgrl's command-line helpers (command_line.hpp).
#include "command_line.hpp"

#include <algorithm>

#include <unistd.h>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"

namespace mgrl::app::cli {

// The capture and cache folders, the same two flags on every command that reads a scenario.
void addData(CLI::App* command, std::string& dataDir) {
  command->add_option(
      "--data", dataDir,
      "Motion capture folder (default: MGRL_DATA, else ~/.local/share/mgrl if it exists, else ../shared/mocap)");
}
void addDataAndCache(CLI::App* command, std::string& dataDir, std::string& cacheDir) {
  addData(command, dataDir);
  command->add_option("--cache", cacheDir, "Cache folder (default: MGRL_CACHE, else ~/.cache/mgrl)");
}

void setPunchMinSpeed(const std::string& text, mgrl::AnnotationParams& params) {
  if (text == "auto") {
    params.punchMinSpeedAuto = true;
    return;
  }
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !(value > 0 && value <= 100))
    throw mgrl::Error(fmt::format("--punch-min-speed: expected a speed in (0, 100] m/s or auto, found '{}'", text));
  params.punchMinSpeed_mps = value;
  params.punchMinSpeedAuto = false;
}

mgrl::RoleOverrides parseRoles(const std::vector<std::string>& pairs) {
  mgrl::RoleOverrides roles;
  for (const std::string& pair : pairs) {
    const auto eq = pair.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == pair.size())
      throw mgrl::Error(fmt::format("--role: expected ROLE=JOINT, found '{}'", pair));
    roles[pair.substr(0, eq)] = pair.substr(eq + 1);
  }
  return roles;
}

// 80 % of the machine's memory, in GB: what training may plan to use by default.
double defaultMaxMemoryGb() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || pageSize <= 0) return 8;
  return 0.8 * static_cast<double>(pages) * static_cast<double>(pageSize) / 1e9;
}

// "a, b,c" -> {"a", "b", "c"}; empty items are kept (as "") so that they are reported.
std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::size_t begin = 0;
  while (true) {
    const std::size_t end = std::min(text.find(',', begin), text.size());
    std::string item = text.substr(begin, end - begin);
    item.erase(0, item.find_first_not_of(' '));
    item.erase(item.find_last_not_of(' ') + 1);
    items.push_back(item);
    if (end == text.size()) break;
    begin = end + 1;
  }
  return items;
}

// Levenshtein distance, for "did you mean".
std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// The first argument of `args` that looks like an option `command` does not know, with the
// nearest known one: "--contoller" -> "--controller". Empty if there is none.
std::string unknownOption(const CLI::App& command, const std::vector<std::string>& args) {
  std::vector<std::string> known;
  for (const CLI::Option* option : command.get_options()) {
    for (const std::string& name : option->get_lnames()) known.push_back("--" + name);
    for (const std::string& name : option->get_snames()) known.push_back("-" + name);
  }
  for (const std::string& arg : args) {
    if (arg.size() < 2 || arg[0] != '-') continue;
    const std::string name = arg.substr(0, arg.find('='));
    if (std::find(known.begin(), known.end(), name) != known.end()) continue;
    std::string best;
    std::size_t bestDistance = std::string::npos;
    for (const std::string& k : known) {
      const std::size_t d = editDistance(name, k);
      if (d < bestDistance) {
        bestDistance = d;
        best = k;
      }
    }
    if (!best.empty() && bestDistance <= std::max<std::size_t>(2, name.size() / 3))
      return fmt::format("{}: unknown option {} (did you mean {}?)", command.get_name(), name, best);
    return fmt::format("{}: unknown option {} (see mgrl {} --help)", command.get_name(), name, command.get_name());
  }
  return {};
}

}  // namespace mgrl::app::cli
