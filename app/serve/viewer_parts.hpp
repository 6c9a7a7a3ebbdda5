#pragma once
// The viewer's page session (viewer.hpp), its parts shared by the files that implement it:
// viewer.cpp (the world, controllers, scene, frames, success), viewer_lesson.cpp (the
// learn panel), viewer_retrain.cpp (live retraining), viewer_values.cpp (the values view).
// Not for other code: include serve/viewer.hpp.
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/learning/q_learning_steps.hpp"
#include "mgrl/learning/success.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/session/session.hpp"
#include "serve/viewer.hpp"

namespace mgrl::serve {

using Clock = std::chrono::steady_clock;

// What costly page messages took of the server's thread, learned as they run, so that the
// next is priced before it runs (ViewerSession::price): seconds per unit of each kind.
struct MessagePrices {
  enum Kind { Mode, LessonStart, LessonSteps, Retrain, kKinds };
  std::array<std::atomic<double>, kKinds> perUnit{};

  /// Seconds; a kind not yet seen on this server is taken to cost `unknown`.
  double price(Kind kind, double units, double unknown) const {
    const double perUnitNow = perUnit[kind].load(std::memory_order_relaxed);
    return perUnitNow == 0 ? unknown : perUnitNow * units;
  }
  // A run that took longer than the price raises it at once; one that took less lowers it
  // by a quarter of the difference: prices err high.
  void learn(Kind kind, double units, double seconds) {
    if (units <= 0) return;
    const double measured = seconds / units, old = perUnit[kind].load(std::memory_order_relaxed);
    perUnit[kind].store(old == 0 ? measured : std::max(measured, 0.75 * old + 0.25 * measured),
                        std::memory_order_relaxed);
  }
};

/// Runs `work` (which must not throw) on a detached thread that waitForWorkers() waits for.
void startWorker(std::function<void()> work);

struct ViewerAssets {
  /// The scenario opened once for every page: graph, behaviours, task and (when one serves)
  /// the policy bundle; session->policy empty: the policy controller is not offered.
  std::unique_ptr<const Session> session;
  /// The tables its worlds play: the session's bundle and, with --partner-policy, the
  /// partners' (Session::withPartner()).
  Policies played;
  double meanOutDegree = 1;  ///< actions per state, for the online search's cost
  std::string note;          ///< shown on the page (no policy bundle, ...)
  /// Shown in sparring and crowds only: what the partners play (--partner-policy).
  std::string partnerNote;
  ServeOptions options;      ///< what the server was started with (live retraining adds --set's)
  /// What eval counts as success (trialCriteria), which the page counts live, and
  /// its text ("contact of the fists within 0.15 m").
  std::vector<SuccessCriterion> criteria;
  std::string criteriaText;
  /// The scenario whose behaviours play sparring and crowds (ServeOptions::sparringScenario),
  /// loaded beside this one at start; null: this scenario's own play every mode.
  std::shared_ptr<const ViewerAssets> sparring;
  /// Learned by every page of the server from the messages it handles (mutable: a price
  /// is not part of what the assets are).
  mutable MessagePrices prices;
  /// The capture's source poses, made once: every page's crowd poses from them instead of
  /// making its own at each change of mode (a forward-kinematics pass over every frame).
  std::shared_ptr<const SourcePoses> sourcePoses;

  const StateActionModel& model() const { return session->model(); }
};

// Decisions timed (paper sec. 6.6 reports the runtime cost of a choice).
struct DecisionClock {
  double seconds = 0;
  std::size_t count = 0;
};

// A behaviour retrained by one page (live retraining): its plugins built with the page's
// changed parameters, value iteration's table on them, and what evaluation said.
struct Retrained {
  std::optional<Scenario> scenario;  ///< the scenario with the page's changes, which `behavior` was built from
  Behavior behavior;
  std::shared_ptr<const Discretizer> refined;  ///< the learner's own grid, if it refined one
  QTable table;
  std::vector<double> vertices;  ///< (vertices, 3) positions, avatar frame
  nlohmann::json set;                      ///< the parameters changed, as the page sent them
  nlohmann::json curve = nlohmann::json::array();    ///< [updates, seconds, residual, mean residual]
  nlohmann::json before, after;            ///< Trials::summary of the policy without and with this table
  double trainSeconds = 0, totalSeconds = 0;
  std::uint64_t updates = 0;

  const Discretizer& grid() const { return refined ? *refined : *behavior.discretizer; }
};

// What a page chose to play (its controller, horizon, weights and policy), and the
// controller that makes in a world of some number of avatars.
struct PageChoices {
  std::string controller;
  int horizon = 3;
  std::vector<double> weights;
  std::vector<PolicyPart> policy;
  std::vector<std::shared_ptr<const Retrained>> retrained;  ///< per behaviour; null: the bundle's
};
struct PageController {
  ControllerParts parts;
  ControllerChoice choice;
  std::string adjustment;                              ///< "" unless the horizon was lowered for the world's size
  std::vector<std::shared_ptr<const Retrained>> keep;  ///< the tables `parts` points into
};
/// The page's choices on `assets`' behaviours for a world of `avatars`: the online search's
/// horizon is lowered where so many avatars would hold up the world. Reads no page state, so
/// a world's first frame can be run with it off the network thread.
PageController pageController(const ViewerAssets& assets, const PageChoices& page, std::size_t avatars);

inline double round3(double x) { return std::round(x * 1000) / 1000; }
inline nlohmann::json point3(const Eigen::Vector3d& p) {
  return nlohmann::json::array({round3(p.x()), round3(p.y()), round3(p.z())});
}

struct ViewerSession::State {
  std::unique_ptr<World> world;
  std::string controller;
  int horizon = 3;
  std::vector<double> weights;
  double speed = 1, carry = 0;
  bool paused = false;
  int steps = 0;
  DecisionClock decisions;
  std::size_t eventsSeen = 0;
  std::deque<double> hitTimes;  ///< simulated times of the hits of the last 30 s
  // Successes as eval counts them: each avatar's actions are followed by the
  // scenario's criteria from the target it decided on, as one trial that restarts at
  // each success. What the model says the action does, like eval's trials: the world's
  // pushes and foot locks are not seen.
  std::vector<std::vector<SuccessCriterion::Tracker>> trackers;  ///< per avatar, one per criterion
  std::vector<std::size_t> decisionsFollowed;                   ///< per avatar
  std::size_t successes = 0;
  std::deque<double> successTimes;  ///< simulated times of the successes of the last 30 s
  FrameWriter writer;
  double busySeconds = 0;       ///< simulating and encoding, since the last stats
  std::size_t busyFrames = 0;
  std::size_t framesShed = 0;  ///< frames dropped at the end of a slice, since the last stats
  std::string adjustment;       ///< what the session changed on its own (scene note)
  int shown = -1;               ///< behaviour whose values are streamed (-1 none)
  std::size_t valuesFrame = 0;  ///< world frame of the last `values` message
  std::string valuesSent;       ///< the last `values` message sent

  // The policy this page runs: the bundle's parts, a retrained behaviour's replaced.
  std::vector<PolicyPart> policy;
  std::vector<std::shared_ptr<const Retrained>> retrained;  ///< per behaviour; null: the bundle's

  // The learn panel: Q-learning a step at a time on one behaviour's problem.
  struct Lesson {
    int behavior = -1;
    std::shared_ptr<const Retrained> keep;  ///< the retrained plugins the lesson's problem uses
    std::unique_ptr<QLearningSteps> steps;
    double rate = 0, carry = 0;  ///< steps per second while running
  };
  std::unique_ptr<Lesson> lesson;

  // A retraining under way on a thread of its own, which holds the job (and everything
  // it reads) jointly with the page: a page that leaves asks it to stop and lets go at
  // once, never waiting for it on the network thread; the thread frees the rest when it
  // ends (waitForWorkers() waits for that when the server stops).
  struct Job {
    int behavior = -1;
    Clock::time_point started;
    std::atomic<bool> stop{false}, done{false};
    std::shared_ptr<Retrained> result;  ///< read once done
    std::string failure;                ///< set instead of a usable result
  };
  std::shared_ptr<Job> job;

  // A world being built on a thread of its own (ViewerSession::buildInBackground), which
  // holds the build jointly with the page: a page that leaves lets go, and the thread frees
  // the world. The page's messages wait until it is installed.
  struct Build {
    Mode mode = Mode::Target;
    std::shared_ptr<const ViewerAssets> assets;  ///< what the new world plays; outlives it
    std::atomic<bool> done{false};
    std::unique_ptr<World> world;  ///< read once done, its first frame run
    std::string failure;           ///< set instead of a world
  };
  std::shared_ptr<Build> build;

  ~State() {
    if (job) job->stop = true;
  }
};

}  // namespace mgrl::serve
