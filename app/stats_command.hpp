#pragma once
/// \file
/// `mgrl stats`: a report on bouts, real or synthesized (docs/stats.md), built by
/// the runtime stage (mgrl/runtime/bout_report.hpp) and printed here.
#include <string>

#include <nlohmann/json.hpp>

#include "mgrl/runtime/bout_report.hpp"

namespace mgrl::app {

/// The report as a text table.
std::string statsText(const nlohmann::json& report);

}  // namespace mgrl::app
