// The viewer's learn panel: Q-learning a step at a time on one behaviour.
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

#include "mgrl/core/numbers.hpp"
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

// The learn panel: the paper's Q-learning (sec. 4.2) on one behaviour's problem
// with a table of the page's own, all zeros at the start, taken a step at a time so that
// each update can be looked at as the paper's Fig. 4 draws it.
void ViewerSession::learn(const Learn& message) {
  State& s = *state_;
  const ViewerAssets& a = *assets_;
  using Command = Learn::Command;
  if (message.command == Command::Start) {
    const int i = behaviorIndex(message.behavior);
    if (i < 0)
      throw Error(fmt::format("learn.behavior: expected one of {}, found \"{}\"", behaviorNames(), message.behavior));
    auto lesson = std::make_unique<State::Lesson>();
    lesson->behavior = i;
    lesson->keep = s.retrained[static_cast<std::size_t>(i)];
    const Behavior& b = lesson->keep ? lesson->keep->behavior : a.session->behaviors[static_cast<std::size_t>(i)];
    const Problem problem = b.problem(a.model());
    const double bytes = QLearningSteps::tableBytes(problem);
    if (bytes > Limits::kLessonBytes)
      throw Error(
          fmt::format("learn: expected a lesson table of at most {} for one page, found {} for {} ({} vertices "
                      "x {} actions); choose a behaviour with a smaller grid",
                      humanBytes(Limits::kLessonBytes), humanBytes(bytes), b.name, b.discretizer->vertexCount(),
                      a.model().actionCount()));
    lesson->steps = std::make_unique<QLearningSteps>(problem, message.budget, message.seed);
    s.lesson = std::move(lesson);
    outbox_.push_back(lessonMessage());
    return;
  }
  if (!s.lesson)
    throw Error("learn.command: expected a lesson started first ({\"type\": \"learn\", \"command\": \"start\", "
                "\"behavior\": ...}), found none");
  State::Lesson& lesson = *s.lesson;
  if (message.command == Command::Stop) {
    s.lesson.reset();
    outbox_.push_back(json{{"type", "lesson"}, {"behavior", nullptr}}.dump());
  } else if (message.command == Command::Run) {
    lesson.rate = message.rate;
    lesson.carry = 0;
  } else {
    if (lesson.steps->done())
      throw Error(fmt::format("learn: the lesson's budget of {} actions is spent; start a new one",
                              lesson.steps->budget()));
    const std::size_t n =
        std::min<std::uint64_t>(static_cast<std::uint64_t>(message.steps), lesson.steps->budget() - lesson.steps->updates());
    QStep last;
    for (std::size_t k = 0; k < n; ++k) last = lesson.steps->step();
    outbox_.push_back(stepMessage(last, n));
  }
}

void ViewerSession::advanceLesson(double frames) {
  State& s = *state_;
  if (!s.lesson || s.lesson->rate <= 0) return;
  State::Lesson& lesson = *s.lesson;
  lesson.carry += frames * frameTime() * lesson.rate;
  // A late timer does not make the lesson race to catch up.
  const double most = std::max(1.0, 8 * frameTime() * Limits::kLearnRateMax);
  auto n = static_cast<std::size_t>(std::min(std::floor(lesson.carry), most));
  lesson.carry = std::min(lesson.carry - static_cast<double>(n), 1.0);
  n = std::min<std::uint64_t>(n, lesson.steps->budget() - lesson.steps->updates());
  if (n == 0) return;
  QStep last;
  for (std::size_t k = 0; k < n; ++k) last = lesson.steps->step();
  if (lesson.steps->done()) lesson.rate = 0;
  outbox_.push_back(stepMessage(last, n));
}

std::string ViewerSession::lessonMessage() const {
  const State& s = *state_;
  const ViewerAssets& a = *assets_;
  const State::Lesson& lesson = *s.lesson;
  const QLearningSteps& steps = *lesson.steps;
  const Behavior& b = lesson.keep ? lesson.keep->behavior : a.session->behaviors[static_cast<std::size_t>(lesson.behavior)];
  json vertices = json::array();
  for (std::size_t v = 0; v < b.discretizer->vertexCount(); ++v) vertices.push_back(point3(b.discretizer->vertexPosition(v)));
  return json{{"type", "lesson"},
              {"behavior", b.name},
              {"budget", steps.budget()},
              {"dimension", b.discretizer->dimension()},
              {"grid", b.discretizer->type()},
              {"vertices", vertices},
              {"states", a.model().stateCount()},
              {"actions", a.model().actionCount()},
              {"pairs", steps.table().vertexCount() * steps.table().actionCount()},
              {"gamma", b.reward->gamma()},
              {"state", steps.state()},
              {"target", point3(steps.target())},
              {"updates", steps.updates()},
              {"restarts", steps.restarts()},
              {"touched", steps.touched()}}
      .dump();
}

std::string ViewerSession::stepMessage(const QStep& step, std::size_t taken) const {
  const State& s = *state_;
  const StateActionModel& model = assets_->model();
  const QLearningSteps& steps = *s.lesson->steps;
  json vertices = json::array();
  for (const QStepVertex& v : step.vertices)
    vertices.push_back({{"vertex", v.vertex},
                        {"position", point3(v.position)},
                        {"weight", v.weight},
                        {"reward", v.reward},
                        {"next", point3(v.next)},
                        {"next_inside", v.nextInside},
                        {"discount", v.discount},
                        {"future", v.future},
                        {"backup", v.backup},
                        {"before", v.before},
                        {"after", v.after}});
  // The action's root path on the floor, in the avatar's frame before it.
  json path = json::array();
  for (std::uint32_t k = model.actionFrameBegin[step.action]; k < model.actionFrameBegin[step.action + 1]; ++k)
    path.push_back({round3(model.frameRoot[3 * k]), 0, round3(model.frameRoot[3 * k + 1])});
  return json{{"type", "learn_step"},
              {"behavior", assets_->session->behaviors[static_cast<std::size_t>(s.lesson->behavior)].name},
              {"update", step.update},
              {"budget", steps.budget()},
              {"taken", taken},
              {"alpha", step.alpha},
              {"state", step.state},
              {"next_state", step.nextState},
              {"action", step.action},
              {"action_index", step.action - model.stateActionBegin[step.state]},
              {"actions", model.stateActionBegin[step.state + 1] - model.stateActionBegin[step.state]},
              {"frames", step.frames},
              {"target", point3(step.target)},
              {"target_next", point3(step.targetNext)},
              {"restarted", step.restarted},
              {"restarts", steps.restarts()},
              {"touched", steps.touched()},
              {"pairs", steps.table().vertexCount() * steps.table().actionCount()},
              {"done", steps.done()},
              {"path", path},
              {"vertices", vertices}}
      .dump();
}

}  // namespace mgrl::serve
