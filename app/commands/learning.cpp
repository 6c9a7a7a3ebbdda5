// `mgrl train`, `mgrl eval`, `mgrl simulate` and `mgrl compare`: behaviours trained,
// measured, played and compared.
#include <cstdint>
#include <string>

#include <unistd.h>

#include <fmt/format.h>

#include "command.hpp"
#include "command_line.hpp"
#include "compare_command.hpp"
#include "learn_commands.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/launch.hpp"

namespace mgrl::app::cli {
namespace {

class Train final : public SessionCommand {
 public:
  Train(CLI::App& app, Common& common)
      : SessionCommand(app.add_subcommand("train",
                                          "Train the scenario's behaviours (paper sec. 4) on its motion graph and "
                                          "save a policy bundle."),
                       common, "Scenario YAML file with a behaviors: section") {
    sub_->add_option("--behavior,--behaviour", options_.behavior,
                     "Train only this behaviour (others in the bundle are kept)");
    sub_->add_option("--out", options_.out, "Policy bundle folder (default: <cache>/policies/<scenario>-<hash>)");
    sub_->add_flag("--resume", options_.resume, "Continue from the checkpoints of an interrupted run");
    sub_->add_option("--max-memory", maxMemoryGb_,
                     "Refuse a behaviour whose training needs more memory than this (GB; default: 80 % of this "
                     "machine's)")
        ->default_str(fmt::format("{:.1f}", maxMemoryGb_));
    sub_->add_option("--model", options_.model,
                     "The learning problem in memory: tabulated (every transition stored, fastest), compact (rewards "
                     "only, about a fifth of the memory, a grid lookup per backup; the same tables), or auto "
                     "(tabulated when it fits in --max-memory, else compact)")
        ->default_str("auto");
    addSessionOptions(options_, common, true,
                      "Override a scenario key, e.g. --set behaviors.hit.learner.budget=1e6 (repeatable)");
  }

  void runSession(const Common& common) override {
    options_.progressBar = ::isatty(2) != 0;
    if (!(maxMemoryGb_ > 0 && maxMemoryGb_ <= 1e6))
      throw Error(fmt::format("--max-memory: expected gigabytes in (0, 1000000], found {}", maxMemoryGb_));
    options_.maxMemoryBytes = maxMemoryGb_ * 1e9;
    if (options_.model != "auto" && options_.model != "tabulated" && options_.model != "compact")
      throw Error(fmt::format("--model: expected auto, tabulated or compact, found '{}'", options_.model));
    const nlohmann::json report = runTrain(options_);
    // Under an MPI launcher, rank 0 speaks for the job.
    if (launchedProcess().rank > 0) return;
    print(common, report, common.json ? std::string() : trainText(report));
  }

 private:
  TrainOptions options_;
  double maxMemoryGb_ = defaultMaxMemoryGb();
};

class Eval final : public SessionCommand {
 public:
  Eval(CLI::App& app, Common& common)
      : SessionCommand(app.add_subcommand(
                           "eval",
                           "Evaluate a trained policy: random starts, a static target in the approach region, up to "
                           "--seconds of motion each; success is what the behaviours' success: keys say (default: an "
                           "effective hit on the target)."),
                       common) {
    sub_->add_option("--policy", options_.policy, "Policy bundle folder (default: the one mgrl train writes)");
    sub_->add_option("--controller", options_.controller,
                     "policy (the trained one), online_search (depth-limited search of the graph for the best "
                     "discounted reward, the baseline of Lee et al. 2002) or random")
        ->default_str("policy");
    sub_->add_option("--horizon", options_.horizon, "online_search: search depth in actions")->default_val(3);
    sub_->add_option("--horizon-seconds", options_.horizonSeconds,
                     "online_search: search every sequence until it covers this much motion (s; at most --horizon "
                     "actions deep)");
    sub_->add_option("--trials", trials_, "Number of trials")->default_val(trials_);
    sub_->add_option("--seed", seed_, "Random seed (the same seed, the same numbers)")->default_val(1);
    sub_->add_option("--seconds", options_.seconds, "Seconds of motion per trial")->default_val(10);
    sub_->add_option("--target-height", options_.targetHeight,
                     "Height of the target (m; default: the scenario's world.target_height, else that of the "
                     "effective hitting points' centroid)");
    addSessionOptions(options_, common, true);
  }

  void runSession(const Common& common) override {
    if (trials_ < 1 || trials_ > 10'000'000)
      throw Error(fmt::format("--trials: expected a number of trials in [1, 10000000], found {}", trials_));
    if (seed_ < 0) throw Error(fmt::format("--seed: expected a whole number >= 0, found {}", seed_));
    options_.trials = static_cast<std::size_t>(trials_);
    options_.seed = static_cast<std::uint64_t>(seed_);
    const nlohmann::json report = runEval(options_);
    print(common, report, common.json ? std::string() : evalText(report));
  }

 private:
  EvalOptions options_;
  long long trials_ = static_cast<long long>(options_.trials);  // options_ is initialised first
  long long seed_ = static_cast<long long>(options_.seed);
};

class Simulate final : public SessionCommand {
 public:
  Simulate(CLI::App& app, Common& common)
      : SessionCommand(app.add_subcommand(
                           "simulate",
                           "Run the world headless (paper sec. 5, 6.6): avatars in sparring pairs (or with targets) "
                           "controlled by the trained policy, collisions at effective punches, reactions; report speed "
                           "and hits, optionally write BVH and hit events."),
                       common) {
    sub_->add_option("--avatars", options_.run.avatars, "Number of avatars (pairs spar; an odd one punches a target)")
        ->default_val(2);
    sub_->add_option("--seconds", options_.run.seconds, "Simulated seconds")->default_val(10);
    sub_->add_option("--seed", seed_, "Random seed (the same seed, the same events and BVH bytes)")->default_val(1);
    sub_->add_option("--bvh-out", options_.run.bvhOut, "Write one BVH per avatar into this folder");
    sub_->add_option("--gltf-out", options_.run.gltfOut,
                     "Write one binary glTF 2.0 (.glb: skeleton, animation, skinned body) per avatar into this "
                     "folder (may be --bvh-out's)");
    sub_->add_option("--events-out", options_.run.eventsOut, "Write the hits as JSON lines to this file");
    sub_->add_option("--policy", options_.policy, "Policy bundle folder (default: the one mgrl train writes)");
    sub_->add_option("--partner-policy", options_.run.partnerPolicy,
                     "Sparring: the second avatar of each pair plays this bundle instead (two policies spar)");
    sub_->add_option("--partner-round", options_.run.partnerRound,
                     "With --partner-policy: the partner plays that self-play round's tables (mgrl train keeps every "
                     "round)")
        ->check(CLI::Range(1, 1000));
    sub_->add_option("--round", options_.run.round,
                     "The policy's avatars play that self-play round's tables instead of the final ones (with "
                     "--partner-round: any two rounds spar)")
        ->check(CLI::Range(1, 1000));
    sub_->add_option("--controller", options_.run.controller.name,
                     controllerAlternatives(requirePlugins(options_.plugins, "SessionOptions::plugins").controllers))
        ->default_str("policy");
    sub_->add_option("--horizon", options_.run.controller.horizon, "online_search: search depth in actions")
        ->default_val(3);
    sub_->add_option("--horizon-seconds", options_.run.controller.horizonSeconds,
                     "online_search: search this much motion instead (s)");
    sub_->add_option("--top-k", options_.run.topK, "Variety: draw among the k best actions (default: world.top_k)");
    sub_->add_flag("--poses", options_.run.poses,
                   "Compute every joint's pose each frame (blending, forward kinematics, reactions); implied by "
                   "--bvh-out and --gltf-out");
    sub_->add_option("--threads", options_.run.threads, "Worker threads (default: all cores)");
    addSessionOptions(options_, common, true);
  }

  void runSession(const Common& common) override {
    if (seed_ < 0) throw Error(fmt::format("--seed: expected a whole number >= 0, found {}", seed_));
    options_.run.seed = static_cast<std::uint64_t>(seed_);
    const nlohmann::json report = runSimulate(options_);
    print(common, report, common.json ? std::string() : simulateText(report));
  }

 private:
  SimulateOptions options_;
  long long seed_ = 1;
};

class Compare final : public SessionCommand {
 public:
  Compare(CLI::App& app, Common& common)
      : SessionCommand(
            app.add_subcommand(
                "compare",
                "Compare learners on one behaviour: train each with each seed on the same graph, evaluate "
                "every policy on the same trials (and snapshots of it along training, for learning curves of "
                "success rate), and measure each table against value iteration's on the same grid or a "
                "finer one (--reference-set)."),
            common) {
    sub_->add_option("--behavior,--behaviour", options_.behavior, "The behaviour whose learner varies")->required();
    sub_->add_option("--learners", learners_, "Comma-separated learners (see mgrl list)")->required();
    sub_->add_option("--seeds", seeds_, "Comma-separated seeds for seeded learners")->default_str("1");
    sub_->add_option("--learner-set", options_.learnerSets,
                     "LEARNER:KEY=VALUE: a parameter of one learner (repeatable), e.g. q_learning:budget=2000000");
    sub_->add_option("--trials", options_.trials, "Evaluation trials per run (the same starts for all)")
        ->default_val(100);
    sub_->add_option("--seconds", options_.seconds, "Motion per trial (s)")->default_val(10);
    sub_->add_option("--snapshots", options_.snapshots,
                     "Policies evaluated along each run's training, at about this many evenly spaced points, for the "
                     "success-rate learning curves (0: none)")
        ->default_val(10);
    sub_->add_option("--snapshot-trials", options_.snapshotTrials,
                     "Trials per snapshot: the first of the same starts (default: 50, at most --trials)");
    sub_->add_option("--reference-set", options_.referenceSets,
                     "KEY=VALUE: a parameter of the behaviour's discretizer for the reference only (repeatable), "
                     "e.g. angles=40: value iteration on that grid, interpolated at each table's vertices");
    sub_->add_option("--report", options_.report,
                     "Write index.html (plots, learning curves), results.json, results.csv and curves.csv here");
    addSessionOptions(options_, common, true);
  }

  void runSession(const Common& common) override {
    options_.learners = splitList(learners_);
    options_.seeds.clear();
    for (const std::string& word : splitList(seeds_)) {
      std::size_t used = 0;
      unsigned long long value = 0;
      try {
        value = std::stoull(word, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != word.size() || word.empty() || word[0] == '-')
        throw Error(fmt::format("--seeds: expected whole numbers >= 0 separated by commas, found '{}'", word));
      options_.seeds.push_back(value);
    }
    if (sub_->get_option("--snapshot-trials")->count() > 0 && options_.snapshotTrials == 0)
      throw Error("--snapshot-trials: expected a number of trials of at least 1, found 0");
    const nlohmann::json report = runCompare(options_);
    print(common, report, common.json ? std::string() : compareText(report));
  }

 private:
  CompareOptions options_;
  std::string learners_, seeds_ = "1";
};

}  // namespace

std::unique_ptr<Command> trainCommand(CLI::App& app, Common& common) { return std::make_unique<Train>(app, common); }
std::unique_ptr<Command> evalCommand(CLI::App& app, Common& common) { return std::make_unique<Eval>(app, common); }
std::unique_ptr<Command> simulateCommand(CLI::App& app, Common& common) {
  return std::make_unique<Simulate>(app, common);
}
std::unique_ptr<Command> compareCommand(CLI::App& app, Common& common) { return std::make_unique<Compare>(app, common); }

}  // namespace mgrl::app::cli
