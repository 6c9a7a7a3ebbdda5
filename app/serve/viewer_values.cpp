// The viewer's values view (paper sec. 5): what the policy saw at avatar 0's last decision.
#include "serve/viewer_parts.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/learning/q_learning_steps.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/session/session.hpp"
#include "mgrl/session/trials.hpp"

namespace mgrl::serve {

namespace fs = std::filesystem;
using json = nlohmann::json;

// What the policy saw at avatar 0's last decision (paper sec. 5): at its state s, for every
// vertex v of the behaviour's grid (a 3-D grid's layer nearest the target's height), the
// value max_a Q(s, v, a) and the greedy action, placed around the avatar as it stood then;
// and the root path of the action it took.
std::string ViewerSession::values() const {
  const ViewerAssets& a = *assets_;
  const State& s = *state_;
  const auto shown = static_cast<std::size_t>(s.shown);
  const Retrained* retrained = s.retrained[shown].get();
  const Behavior& behavior = retrained ? retrained->behavior : a.session->behaviors[shown];
  const std::vector<double>& vertexPositions =
      retrained ? retrained->vertices : a.session->bundle.behaviors.at(behavior.name).vertices;
  const QTable& q = *s.policy[shown].table;
  const World::Decision d = s.world->lastDecision(0);
  const Eigen::Vector3d e = inverseTransformPoint(d.frame, s.world->seen(0));
  // Where the target is now, in the decision's frame, moving as the controller saw it.
  TargetState seenNow = d.target;
  seenNow.position = e;
  // A grid that also holds the target's heading (polar_velocity) repeats each position per
  // heading and speed layer, and per turn layer for a turning target: show the positions at
  // the target's motion as the controller saw it, the turn layer of its turn rate, the
  // speed layer nearest its speed and the heading nearest its heading (a standing target,
  // one the page dragged: the straight, speed-0 layers; an opponent's facing is
  // its heading too). A learned opponent's layers show its first state.
  const Discretizer& grid = *s.policy[shown].grid;
  const GridAxis* heading = grid.axis(AxisRole::Heading);
  std::size_t vertices = grid.turnAxis() ? grid.turnVertexCount() : q.vertexCount();
  if (grid.layerAxis()) {  // the positions of one heading and layer
    vertices = 1;
    for (const GridAxis& axis : grid.axes())
      if (axis.role != AxisRole::Heading) vertices *= axis.vertices.size();
  }
  // The index of the vertex of `axis` nearest c (the first of equals), by `gap`.
  auto nearest = [](const std::vector<double>& axis, auto gap) {
    std::size_t best = 0;
    for (std::size_t k = 1; k < axis.size(); ++k)
      if (gap(axis[k]) < gap(axis[best])) best = k;
    return best;
  };
  const std::size_t turnLayer = grid.turnLayer(d.target.turnRate);
  std::size_t offset = turnLayer * grid.turnVertexCount();
  double layerSpeed = 0;
  if (const GridAxis* speeds = grid.axis(AxisRole::Speed)) {
    const std::size_t k = nearest(speeds->vertices, [&](double v) { return std::abs(v - d.target.speed); });
    offset += k * grid.layerVertexCount();
    layerSpeed = speeds->vertices[k];
  }
  if (grid.layerAxis() && heading)
    offset += vertices * nearest(heading->vertices,
                                 [&](double v) { return std::abs(std::remainder(v - d.target.heading, 2 * M_PI)); });
  double level = vertexPositions.empty() ? 0 : vertexPositions[3 * offset + 1];
  for (std::size_t v = offset; v < offset + vertices; ++v)
    if (std::abs(vertexPositions[3 * v + 1] - e.y()) < std::abs(level - e.y())) level = vertexPositions[3 * v + 1];
  const std::size_t n = q.actionsOf(d.state);
  json points = json::array();
  double lo = 0, hi = 0;
  bool first = true;
  for (std::size_t v = offset; v < offset + vertices; ++v) {
    const double* p = &vertexPositions[3 * v];
    if (std::abs(p[1] - level) > 1e-6 || n == 0) continue;
    const float* row = q.row(d.state, v);
    const std::size_t best = static_cast<std::size_t>(std::max_element(row, row + n) - row);
    const Eigen::Vector3d w = transformPoint(d.frame, {p[0], p[1], p[2]});
    const double value = row[best];
    lo = first ? value : std::min(lo, value);
    hi = first ? value : std::max(hi, value);
    first = false;
    points.push_back({std::round(w.x() * 1000) / 1000, std::round(w.y() * 1000) / 1000, std::round(w.z() * 1000) / 1000,
                      value, best});
  }
  const StateActionModel& model = a.model();
  json path = json::array();
  for (std::uint32_t k = model.actionFrameBegin[d.action]; k < model.actionFrameBegin[d.action + 1]; ++k) {
    const Eigen::Vector3d w = transformPoint(d.frame, {model.frameRoot[3 * k], 0, model.frameRoot[3 * k + 1]});
    path.push_back({std::round(w.x() * 1000) / 1000, 0, std::round(w.z() * 1000) / 1000});
  }
  return json{{"type", "values"},
              {"behavior", behavior.name},
              {"avatar", 0},
              {"time", s.world->time()},
              {"state", d.state},
              {"actions", n},
              {"chosen", d.action - model.stateActionBegin[d.state]},
              {"height", level},
              {"target_inside", s.policy[shown].grid->inside(seenNow)},
              {"speed", layerSpeed},
              {"turn_deg_s", grid.turnAxis() ? grid.turnAxis()->vertices[turnLayer] * 180 / M_PI : 0.0},
              // Stances: the one avatar 0 held at the decision, and the shown
              // behaviour's (it played only if they are the same); null for none.
              {"stance", d.target.stance >= 0 ? json(d.target.stance) : json(nullptr)},
              {"behavior_stance", behavior.stance >= 0 ? json(behavior.stance) : json(nullptr)},
              {"v_min", lo},
              {"v_max", hi},
              {"points", points},
              {"path", path}}
      .dump();
}

}  // namespace mgrl::serve
