#pragma once
/// \file
/// `mgrl graph SCENARIO`: builds (or reuses from the cache) a scenario's motion graph and
/// state-action model, and reports its size.
#include <string>

#include <nlohmann/json.hpp>

#include "mgrl/session/graph_source.hpp"

namespace mgrl::app {

nlohmann::json graphJson(const GraphResult& graph);
std::string graphText(const GraphResult& graph);

}  // namespace mgrl::app
