// The mgrl command line (DESIGN.md sec. 5). Errors: one line on stderr, non-zero exit;
// --json: one JSON object on stdout and nothing else there.

#include <algorithm>
#include <string>
#include <vector>
#include <cstdio>
#include <iostream>

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "command_line.hpp"
#include "compare_command.hpp"
#include "graph_command.hpp"
#include "init_command.hpp"
#include "inspect.hpp"
#include "learn_commands.hpp"
#include "plugins.hpp"
#include "serve/serve_command.hpp"
#include "stats_command.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/core/data_paths.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/version.hpp"

using namespace mgrl::app::cli;  // NOLINT: the command line's own helpers (command_line.hpp)

namespace {

constexpr int kExitError = 1;
constexpr int kExitUsage = 2;
constexpr int kExitInterrupted = 130;  // as a shell reports a Ctrl-C

}  // namespace

int main(int argc, char** argv) {
  // `mgrl stats --compare REAL... -- SYNTH...`: what follows `--` is the second group.
  // CLI11 would fold it into the positionals, so it is cut off before parsing.
  std::vector<std::string> statsAfterDash;
  bool statsDash = false;
  if (argc > 1 && std::string(argv[1]) == "stats")
    for (int i = 2; i < argc; ++i)
      if (std::string(argv[i]) == "--") {
        statsAfterDash.assign(argv + i + 1, argv + argc);
        statsDash = true;
        argc = i;
        break;
      }
  CLI::App app{"mgrl: train avatar behaviours from unlabelled motion capture with reinforcement learning on a "
               "motion graph (after Lee & Lee, SCA 2004)."};
  app.set_version_flag("--version", std::string("mgrl ") + mgrl::kVersion);
  app.require_subcommand(1);

  mgrl::app::InspectOptions inspect;
  bool json = false;
  std::string units = "auto";
  std::string asf;
  std::vector<std::string> roles;
  std::vector<std::string> files;
  CLI::App* inspectCommand = app.add_subcommand(
      "inspect", "Read motion files (.bvh, .amc) and report joints, frames, fps, duration, height, foot contacts "
                 "and effective hits (paper sec. 6.2).");
  inspectCommand->add_option("FILE", files, "Motion files")->required();
  inspectCommand->add_flag("--json", json, "Print one JSON object on stdout");
  inspectCommand->add_option("--fps", inspect.load.fps, "Resample to this frame rate before annotating");
  inspectCommand->add_option("--units", units, "Length units of the files: auto, m, cm, inch, cmu")
      ->default_str("auto");
  inspectCommand->add_option("--asf", asf, "Skeleton for .amc files (default: <subject>.asf beside each)");
  inspectCommand->add_option("--role", roles, "Set a skeleton role, e.g. --role left_fist=LeftHand (repeatable)");
  inspectCommand->add_option("--punch-min-speed", inspect.annotation.punchMinSpeed_mps,
                             "Effective punch: minimum fist speed along the forearm (m/s)")
      ->default_val(inspect.annotation.punchMinSpeed_mps);
  inspectCommand->add_option("--punch-min-body-speed", inspect.annotation.punchMinBodySpeed_mps,
                             "Effective punch: the fist drives out from the body at this speed along the forearm, "
                             "relative to the pelvis, at one frame at least (m/s; 0: arm swings count too)")
      ->default_val(inspect.annotation.punchMinBodySpeed_mps);

  mgrl::app::InitOptions init;
  std::vector<std::string> initFiles;
  std::string initOut, initUnits = "auto", initData;
  std::vector<std::string> initRoles;
  CLI::App* initCommand = app.add_subcommand(
      "init", "Start a scenario for your own motion files: inspect them, choose graph settings that keep most "
              "frames, size the grids to the capture, pick behaviours it can do, write a commented scenario and "
              "print the commands that build, train and view it (docs/own-capture.md).");
  initCommand->add_option("FILE", initFiles, "Motion files (.bvh, .amc) of one skeleton")->required();
  initCommand->add_option("--out", initOut, "Scenario to write (default: NAME.yaml in the current folder)");
  initCommand->add_option("--name", init.name, "Scenario name (default: from the first file's name)");
  initCommand->add_option("--data", initData, "Data folder for relative paths (default: MGRL_DATA, else ../shared/mocap)");
  initCommand->add_option("--fps", init.fps, "Frame rate of the scenario")->default_val(init.fps);
  initCommand->add_option("--units", initUnits, "Length units of the files: auto, m, cm, inch, cmu")->default_str("auto");
  initCommand->add_option("--role", initRoles, "Set a skeleton role, e.g. --role left_fist=LeftHand (repeatable)");
  initCommand->add_flag("--force", init.force, "Replace an existing scenario file");
  initCommand->add_flag("--json", json, "Print one JSON object on stdout");

  std::string scenarioPath, dataDir, cacheDir;
  bool noCache = false;
  CLI::App* graphCommand = app.add_subcommand(
      "graph", "Build a scenario's motion graph and state-action model (paper sec. 3, 6.3), or reuse it from the "
               "cache, and report its size.");
  graphCommand->add_option("SCENARIO", scenarioPath, "Scenario YAML file (see scenarios/README.md)")->required();
  graphCommand->add_flag("--json", json, "Print one JSON object on stdout");
  addDataAndCache(graphCommand, dataDir, cacheDir);
  graphCommand->add_flag("--no-cache", noCache, "Rebuild even if a matching cached graph exists");
  std::vector<std::string> graphSets;
  graphCommand->add_option("--set", graphSets, "Override a scenario key, e.g. --set graph.threshold=0.5 (repeatable)");

  mgrl::app::TrainOptions train;
  CLI::App* trainCommand = app.add_subcommand(
      "train", "Train the scenario's behaviours (paper sec. 4) on its motion graph and save a policy bundle.");
  trainCommand->add_option("SCENARIO", scenarioPath, "Scenario YAML file with a behaviors: section")->required();
  trainCommand->add_option("--behavior,--behaviour", train.behavior, "Train only this behaviour (others in the bundle are kept)");
  trainCommand->add_option("--set", train.sets, "Override a scenario key, e.g. --set behaviors.hit.learner.budget=1e6 "
                                                "(repeatable)");
  trainCommand->add_option("--out", train.out, "Policy bundle folder (default: <cache>/policies/<scenario>-<hash>)");
  trainCommand->add_flag("--resume", train.resume, "Continue from the checkpoints of an interrupted run");
  double maxMemoryGb = defaultMaxMemoryGb();
  trainCommand->add_option("--max-memory", maxMemoryGb,
                           "Refuse a behaviour whose training needs more memory than this (GB; default: 80 % of "
                           "this machine's)")
      ->default_str(fmt::format("{:.1f}", maxMemoryGb));
  trainCommand
      ->add_option("--model", train.model,
                   "The learning problem in memory: tabulated (every transition stored, fastest), compact (rewards "
                   "only, about a fifth of the memory, a grid lookup per backup; the same tables), or auto "
                   "(tabulated when it fits in --max-memory, else compact)")
      ->default_str("auto");
  trainCommand->add_flag("--json", json, "Print one JSON object on stdout");
  addDataAndCache(trainCommand, dataDir, cacheDir);

  mgrl::app::EvalOptions eval;
  long long trials = static_cast<long long>(eval.trials);
  long long seed = static_cast<long long>(eval.seed);
  CLI::App* evalCommand = app.add_subcommand(
      "eval", "Evaluate a trained policy: random starts, a static target in the approach region, up to --seconds of "
              "motion each; success is what the behaviours' success: keys say (default: an effective hit on the target).");
  evalCommand->add_option("SCENARIO", scenarioPath, "Scenario YAML file")->required();
  evalCommand->add_option("--policy", eval.policy, "Policy bundle folder (default: the one mgrl train writes)");
  evalCommand->add_option("--controller", eval.controller,
                          "policy (the trained one), online_search (depth-limited search of the graph for the best "
                          "discounted reward, the baseline of Lee et al. 2002) or random")
      ->default_str("policy");
  evalCommand->add_option("--horizon", eval.horizon, "online_search: search depth in actions")->default_val(3);
  evalCommand->add_option("--horizon-seconds", eval.horizonSeconds,
                          "online_search: search every sequence until it covers this much motion (s; at most "
                          "--horizon actions deep)");
  evalCommand->add_option("--trials", trials, "Number of trials")->default_val(trials);
  evalCommand->add_option("--seed", seed, "Random seed (the same seed, the same numbers)")->default_val(1);
  evalCommand->add_option("--seconds", eval.seconds, "Seconds of motion per trial")->default_val(10);
  evalCommand->add_option("--target-height", eval.targetHeight,
                          "Height of the target (m; default: the scenario's world.target_height, else that of the effective hitting points' centroid)");
  evalCommand->add_option("--set", eval.sets, "Override a scenario key (repeatable)");
  evalCommand->add_flag("--json", json, "Print one JSON object on stdout");
  addDataAndCache(evalCommand, dataDir, cacheDir);

  mgrl::app::SimulateOptions simulate;
  long long simulateSeed = 1;
  CLI::App* simulateCommand = app.add_subcommand(
      "simulate", "Run the world headless (paper sec. 5, 6.6): avatars in sparring pairs (or with targets) "
                  "controlled by the trained policy, collisions at effective punches, reactions; report speed and "
                  "hits, optionally write BVH and hit events.");
  simulateCommand->add_option("SCENARIO", scenarioPath, "Scenario YAML file")->required();
  simulateCommand->add_option("--avatars", simulate.avatars, "Number of avatars (pairs spar; an odd one punches a "
                                                             "target)")->default_val(2);
  simulateCommand->add_option("--seconds", simulate.seconds, "Simulated seconds")->default_val(10);
  simulateCommand->add_option("--seed", simulateSeed, "Random seed (the same seed, the same events and BVH bytes)")
      ->default_val(1);
  simulateCommand->add_option("--bvh-out", simulate.bvhOut, "Write one BVH per avatar into this folder");
  simulateCommand->add_option("--events-out", simulate.eventsOut, "Write the hits as JSON lines to this file");
  simulateCommand->add_option("--policy", simulate.policy, "Policy bundle folder (default: the one mgrl train writes)");
  simulateCommand->add_option("--controller", simulate.controller, "policy, online_search or random")
      ->default_str("policy");
  simulateCommand->add_option("--horizon", simulate.horizon, "online_search: search depth in actions")->default_val(3);
  simulateCommand->add_option("--horizon-seconds", simulate.horizonSeconds,
                              "online_search: search this much motion instead (s)");
  simulateCommand->add_option("--top-k", simulate.topK, "Variety: draw among the k best actions (default: world.top_k)");
  simulateCommand->add_flag("--poses", simulate.poses,
                            "Compute every joint's pose each frame (blending, forward kinematics, reactions); "
                            "implied by --bvh-out");
  simulateCommand->add_option("--threads", simulate.threads, "Worker threads (default: all cores)");
  simulateCommand->add_option("--set", simulate.sets, "Override a scenario key (repeatable)");
  simulateCommand->add_flag("--json", json, "Print one JSON object on stdout");
  addDataAndCache(simulateCommand, dataDir, cacheDir);

  mgrl::app::CompareOptions compare;
  std::string compareLearners, compareSeeds = "1";
  CLI::App* compareCommand = app.add_subcommand(
      "compare", "Compare learners on one behaviour: train each with each seed on the same graph, evaluate every "
                 "policy on the same trials (and snapshots of it along training, for learning curves of success "
                 "rate), and measure each table against value iteration's on the same grid or a finer one "
                 "(--reference-set).");
  compareCommand->add_option("SCENARIO", scenarioPath, "Scenario YAML file")->required();
  compareCommand->add_option("--behavior,--behaviour", compare.behavior, "The behaviour whose learner varies")
      ->required();
  compareCommand->add_option("--learners", compareLearners, "Comma-separated learners (see mgrl list)")->required();
  compareCommand->add_option("--seeds", compareSeeds, "Comma-separated seeds for seeded learners")->default_str("1");
  compareCommand->add_option("--learner-set", compare.learnerSets,
                             "LEARNER:KEY=VALUE: a parameter of one learner (repeatable), e.g. q_learning:budget=2000000");
  compareCommand->add_option("--trials", compare.trials, "Evaluation trials per run (the same starts for all)")
      ->default_val(100);
  compareCommand->add_option("--seconds", compare.seconds, "Motion per trial (s)")->default_val(10);
  compareCommand->add_option("--snapshots", compare.snapshots,
                             "Policies evaluated along each run's training, at about this many evenly spaced points, "
                             "for the success-rate learning curves (0: none)")
      ->default_val(10);
  compareCommand->add_option("--snapshot-trials", compare.snapshotTrials,
                             "Trials per snapshot: the first of the same starts (default: 50, at most --trials)");
  compareCommand->add_option("--reference-set", compare.referenceSets,
                             "KEY=VALUE: a parameter of the behaviour's discretizer for the reference only (repeatable), "
                             "e.g. angles=40: value iteration on that grid, interpolated at each table's vertices");
  compareCommand->add_option("--report", compare.report, "Write index.html (plots, learning curves), results.json, results.csv and curves.csv here");
  compareCommand->add_option("--set", compare.sets, "Override a scenario key (repeatable)");
  compareCommand->add_flag("--json", json, "Print one JSON object on stdout");
  addDataAndCache(compareCommand, dataDir, cacheDir);

  mgrl::serve::ServeCommandOptions serve;
  CLI::App* serveCommand = app.add_subcommand(
      "serve", "Serve the interactive viewer (paper sec. 6.6, 6.7) in the browser: drag a target for a boxer, watch "
               "two boxers spar or a crowd of them; switch controllers and weights live (docs/viewer-protocol.md).");
  serveCommand->add_option("SCENARIO", scenarioPath, "Scenario YAML file")->required();
  serveCommand->add_option("--policy", serve.policy,
                           "Policy bundle folder (default: the one mgrl train writes; none: the online search runs)");
  serveCommand->add_option("--host", serve.host, "Address to listen on (other than 127.0.0.1: reachable from other "
                                                 "machines)")->default_str("127.0.0.1");
  serveCommand->add_option("--port", serve.port, "Port (0: any free one; the URL is printed)")->default_val(8080);
  serveCommand->add_flag("--open", serve.open, "Open the page in the desktop's browser (xdg-open)");
  serveCommand->add_option("--allow-origin", serve.allowOrigins,
                           "Also answer pages of this origin, e.g. http://mybox.lan:8080 (repeatable; by default only "
                           "the server's own address, localhost, 127.0.0.1 and [::1] at its port)");
  serveCommand->add_option("--web", serve.web, "The viewer's folder (default: MGRL_WEB, else the repository's web/)");
  serveCommand->add_option("--set", serve.sets, "Override a scenario key (repeatable)");
  addDataAndCache(serveCommand, dataDir, cacheDir);

  mgrl::app::StatsOptions stats;
  CLI::App* statsCommand = app.add_subcommand(
      "stats", "Report on bouts, real or synthesized (issue 18, docs/stats.md): pelvis distance and facing "
               "distributions, effective and landed strikes per fighter-minute, planted-foot speed, root direction "
               "reversals, joint steps, interpenetration. BOUT: a folder of BVH files (one per fighter, one world "
               "frame; e.g. simulate --bvh-out's) or a quoted pattern such as "
               "'snu_martial_arts/motion/s_005_1_*.bvh'.");
  statsCommand->add_option("BOUT", stats.bouts, "Bouts: folders or quoted file patterns (relative: the working "
                                                "folder, else the data folder)");
  statsCommand->add_flag("--snu", stats.snu, "Add every real SNU sparring bout (s_TTT_K_*.bvh grouped by TTT_K)");
  statsCommand->add_flag("--compare", stats.compare,
                         "Compare two groups: mgrl stats --compare REAL... -- SYNTH... (W1: Wasserstein-1 "
                         "distance between the pooled distributions)");
  statsCommand->add_option("--land-radius", stats.params.landRadius_m,
                           "A strike lands within this distance of the opponent's body capsules (m)")
      ->default_val(stats.params.landRadius_m);
  statsCommand->add_option("--close-distance", stats.params.closeDistance_m,
                           "Pelvises closer than this count as interpenetrating (m)")
      ->default_val(stats.params.closeDistance_m);
  statsCommand->add_option("--reversal-min-speed", stats.params.reversalMinSpeed_mps,
                           "Root steps slower than this are ignored by the reversal count (m/s)")
      ->default_val(stats.params.reversalMinSpeed_mps);
  statsCommand->add_option("--punch-min-body-speed", stats.params.annotation.punchMinBodySpeed_mps,
                           "Effective punch: the fist drives out from the body at this speed along the forearm, "
                           "relative to the pelvis, at one frame at least (m/s; 0: arm swings count too)")
      ->default_val(stats.params.annotation.punchMinBodySpeed_mps);
  statsCommand->add_flag("--json", json, "Print one JSON object on stdout");
  addData(statsCommand, dataDir);

  CLI::App* listCommand =
      app.add_subcommand("list", "List every registered discretizer, reward, environment model and learner with its "
                                 "parameters, defaults and units.");
  listCommand->add_flag("--json", json, "Print one JSON object on stdout");

  // CLI11 would call an unknown command a missing one; name it instead.
  if (argc > 1 && argv[1][0] != '-') {
    std::vector<std::string> known;
    for (const CLI::App* command : app.get_subcommands({})) known.push_back(command->get_name());
    if (std::find(known.begin(), known.end(), argv[1]) == known.end()) {
      std::cerr << fmt::format("mgrl: expected a command ({}), found '{}' (see mgrl --help)\n", fmt::join(known, ", "),
                               argv[1]);
      return kExitUsage;
    }
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // CLI11 says only "arguments were not expected": name the option and the nearest one.
    if (argc > 1) {
      const std::vector<std::string> args(argv + 2, argv + argc);
      for (const CLI::App* command : app.get_subcommands({}))
        if (command->get_name() == argv[1]) {
          const std::string unknown = unknownOption(*command, args);
          if (!unknown.empty()) {
            std::cerr << "mgrl: " << unknown << '\n';
            return kExitUsage;
          }
        }
    }
    std::cerr << "mgrl: " << e.what() << " (see mgrl --help)\n";
    return kExitUsage;
  }

  try {
    if (inspectCommand->parsed()) {
      if (inspect.load.fps < 0 || inspect.load.fps > 10000)
        throw mgrl::Error(fmt::format("--fps: expected a frame rate in (0, 10000], found {}", inspect.load.fps));
      try {
        inspect.load.units = mgrl::parseLengthUnit(units);
      } catch (const mgrl::Error& e) {
        throw mgrl::Error(fmt::format("--units: {}", e.what()));
      }
      inspect.load.asf = asf;
      inspect.load.warn = [](const std::string& message) { std::cerr << "mgrl: warning: " << message << '\n'; };
      inspect.roles = parseRoles(roles);
      inspect.annotation.validate();
      // Read everything first: on any error, stdout stays empty.
      std::vector<mgrl::app::FileReport> reports;
      for (const std::string& file : files) reports.push_back(mgrl::app::inspectFile(file, inspect));
      if (json)
        std::cout << mgrl::app::toJson(reports).dump(2) << '\n';
      else
        std::cout << mgrl::app::toText(reports);
    }
    if (initCommand->parsed()) {
      for (const std::string& file : initFiles) init.files.emplace_back(file);
      init.out = initOut;
      init.dataDir = mgrl::dataDirectory(initData);
      try {
        init.units = mgrl::parseLengthUnit(initUnits);
      } catch (const mgrl::Error& e) {
        throw mgrl::Error(fmt::format("--units: {}", e.what()));
      }
      init.roles = parseRoles(initRoles);
      init.log = [](const std::string& message) { std::cerr << "mgrl: " << message << '\n'; };
      const nlohmann::json report = mgrl::app::runInit(init);
      if (json)
        std::cout << report.dump(2) << '\n';
      else
        std::cout << mgrl::app::initText(report);
    }
    if (graphCommand->parsed()) {
      const mgrl::Scenario scenario = mgrl::loadScenario(scenarioPath, mgrl::dataDirectory(dataDir), graphSets);
      // The whole scenario, behaviours included, so that `graph` does not pass a file `train` refuses.
      mgrl::checkBehaviors(scenario, mgrl::app::plugins());
      mgrl::app::GraphOptions options;
      options.cacheDir = cacheDir;
      options.noCache = noCache;
      options.log = [](const std::string& message) { std::cerr << "mgrl: " << message << '\n'; };
      mgrl::app::GraphResult graph = mgrl::app::obtainGraph(scenario, options);
      mgrl::app::measurePlayback(graph, scenario.graph.blendFrames);
      if (json)
        std::cout << mgrl::app::graphJson(graph).dump(2) << '\n';
      else
        std::cout << mgrl::app::graphText(graph);
    }
    auto log = [](const std::string& message) { std::cerr << "mgrl: " << message << '\n'; };
    if (trainCommand->parsed()) {
      train.scenario = scenarioPath;
      train.dataDir = dataDir;
      train.cacheDir = cacheDir;
      train.log = log;
      train.progressBar = ::isatty(2) != 0;
      if (!(maxMemoryGb > 0 && maxMemoryGb <= 1e6))
        throw mgrl::Error(fmt::format("--max-memory: expected gigabytes in (0, 1000000], found {}", maxMemoryGb));
      train.maxMemoryBytes = maxMemoryGb * 1e9;
      if (train.model != "auto" && train.model != "tabulated" && train.model != "compact")
        throw mgrl::Error(fmt::format("--model: expected auto, tabulated or compact, found '{}'", train.model));
      const nlohmann::json report = mgrl::app::runTrain(train);
      if (json)
        std::cout << report.dump(2) << '\n';
      else
        std::cout << mgrl::app::trainText(report);
    }
    if (evalCommand->parsed()) {
      eval.scenario = scenarioPath;
      eval.dataDir = dataDir;
      eval.cacheDir = cacheDir;
      eval.log = log;
      if (trials < 1 || trials > 10'000'000)
        throw mgrl::Error(fmt::format("--trials: expected a number of trials in [1, 10000000], found {}", trials));
      if (seed < 0) throw mgrl::Error(fmt::format("--seed: expected a whole number >= 0, found {}", seed));
      eval.trials = static_cast<std::size_t>(trials);
      eval.seed = static_cast<std::uint64_t>(seed);
      const nlohmann::json report = mgrl::app::runEval(eval);
      if (json)
        std::cout << report.dump(2) << '\n';
      else
        std::cout << mgrl::app::evalText(report);
    }
    if (simulateCommand->parsed()) {
      simulate.scenario = scenarioPath;
      simulate.dataDir = dataDir;
      simulate.cacheDir = cacheDir;
      simulate.log = log;
      if (simulateSeed < 0)
        throw mgrl::Error(fmt::format("--seed: expected a whole number >= 0, found {}", simulateSeed));
      simulate.seed = static_cast<std::uint64_t>(simulateSeed);
      const nlohmann::json report = mgrl::app::runSimulate(simulate);
      if (json)
        std::cout << report.dump(2) << '\n';
      else
        std::cout << mgrl::app::simulateText(report);
    }
    if (compareCommand->parsed()) {
      compare.scenario = scenarioPath;
      compare.dataDir = dataDir;
      compare.cacheDir = cacheDir;
      compare.log = log;
      compare.learners = splitList(compareLearners);
      compare.seeds.clear();
      for (const std::string& word : splitList(compareSeeds)) {
        std::size_t used = 0;
        unsigned long long value = 0;
        try {
          value = std::stoull(word, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used != word.size() || word.empty() || word[0] == '-')
          throw mgrl::Error(fmt::format("--seeds: expected whole numbers >= 0 separated by commas, found '{}'", word));
        compare.seeds.push_back(value);
      }
      if (compareCommand->get_option("--snapshot-trials")->count() > 0 && compare.snapshotTrials == 0)
        throw mgrl::Error("--snapshot-trials: expected a number of trials of at least 1, found 0");
      const nlohmann::json report = mgrl::app::runCompare(compare);
      if (json)
        std::cout << report.dump(2) << '\n';
      else
        std::cout << mgrl::app::compareText(report);
    }
    if (serveCommand->parsed()) {
      serve.scenario = scenarioPath;
      serve.dataDir = dataDir;
      serve.cacheDir = cacheDir;
      serve.log = log;
      serve.announce = [&](const std::string& url) {
        std::cout << fmt::format("serving {} at {} (Ctrl-C stops)", scenarioPath, url) << std::endl;
      };
      mgrl::serve::runServe(serve);
    }
    if (statsCommand->parsed()) {
      if (statsDash && !stats.compare)
        throw mgrl::Error("stats: expected --compare before a '--' (mgrl stats --compare REAL... -- SYNTH...)");
      if (stats.compare && !statsDash)
        throw mgrl::Error("--compare: expected REAL... -- SYNTH..., found no '--'");
      for (const std::string& word : statsAfterDash)
        if (word.size() > 1 && word[0] == '-')
          throw mgrl::Error(fmt::format("--compare: expected options before '--', found '{}' after it", word));
      stats.synthetic = statsAfterDash;
      stats.dataDir = mgrl::dataDirectory(dataDir);
      stats.warn = [](const std::string& message) { std::cerr << "mgrl: warning: " << message << '\n'; };
      if (::isatty(2)) stats.log = log;  // progress only on a terminal
      const nlohmann::json report = mgrl::app::runStats(stats);
      if (json)
        std::cout << report.dump(2) << '\n';
      else
        std::cout << mgrl::app::statsText(report);
    }
    if (listCommand->parsed()) {
      if (json)
        std::cout << mgrl::app::listJson(mgrl::app::plugins()).dump(2) << '\n';
      else
        std::cout << mgrl::app::listText(mgrl::app::plugins());
    }
  } catch (const mgrl::app::Interrupted& e) {
    std::cerr << "mgrl: " << e.what() << '\n';
    return kExitInterrupted;
  } catch (const mgrl::Error& e) {
    std::cerr << "mgrl: " << e.what() << '\n';
    return kExitError;
  } catch (const std::exception& e) {
    std::cerr << "mgrl: internal error: " << e.what() << '\n';
    return kExitError;
  }
  return 0;
}
