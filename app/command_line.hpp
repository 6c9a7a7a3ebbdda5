#pragma once
/// \file
/// What `mgrl`'s command line (app/main.cpp) needs beyond CLI11: the flags every command
/// that reads a scenario shares, the parsing of list and ROLE=JOINT arguments, and the
/// "did you mean" message for an unknown option. main.cpp declares the commands; this file
/// changes when an argument's syntax or a shared flag does.
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "mgrl/motion/annotation.hpp"
#include "mgrl/motion/roles.hpp"

namespace mgrl::app::cli {

/// --data (the capture folder), on every command that reads capture.
void addData(CLI::App* command, std::string& dataDir);
/// --data and --cache, on every command that reads a scenario.
void addDataAndCache(CLI::App* command, std::string& dataDir, std::string& cacheDir);

/// --role ROLE=JOINT pairs; throws mgrl::Error ("--role: expected ROLE=JOINT, found 'x'").
mgrl::RoleOverrides parseRoles(const std::vector<std::string>& pairs);
/// --punch-min-speed SPEED|auto into `params`; throws mgrl::Error ("--punch-min-speed:
/// expected a speed in m/s or auto, found 'x'").
void setPunchMinSpeed(const std::string& text, mgrl::AnnotationParams& params);
/// 80 % of the machine's memory, in GB: what training may plan to use by default.
double defaultMaxMemoryGb();
/// "a, b,c" -> {"a", "b", "c"}; empty items are kept (as "") so that they are reported.
std::vector<std::string> splitList(const std::string& text);
/// Levenshtein distance, for "did you mean".
std::size_t editDistance(const std::string& a, const std::string& b);
/// The first argument of `args` that looks like an option `command` does not know, with the
/// nearest known one: "--contoller" -> "--controller". Empty if there is none.
std::string unknownOption(const CLI::App& command, const std::vector<std::string>& args);

}  // namespace mgrl::app::cli
