#pragma once
/// \file
/// `mgrl graph SCENARIO`: builds (or reuses from the cache) a scenario's motion graph and
/// state-action model, and reports its size.
#include <string>

#include <nlohmann/json.hpp>

#include "mgrl/session/graph_source.hpp"

namespace mgrl::app {

// The graph's source moved to the session stage (framework/include/mgrl/session/graph_source.hpp).
using mgrl::CaptureTravel;
using mgrl::defaultCacheDirectory;
using mgrl::GraphOptions;
using mgrl::GraphResult;
using mgrl::measurePlayback;
using mgrl::measureTravel;
using mgrl::obtainGraph;
using mgrl::since;
using mgrl::walkTravel;

nlohmann::json graphJson(const GraphResult& graph);
std::string graphText(const GraphResult& graph);

}  // namespace mgrl::app
