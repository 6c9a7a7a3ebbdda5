// `mgrl serve`, `mgrl stats` and `mgrl list`: the viewer, bout statistics and the plug-ins.
#include <unistd.h>

#include <fmt/format.h>

#include "command.hpp"
#include "command_line.hpp"
#include "plugins.hpp"
#include "serve/serve_command.hpp"
#include "stats_command.hpp"
#include "mgrl/core/data_paths.hpp"
#include "mgrl/core/error.hpp"

namespace mgrl::app::cli {
namespace {

class Serve final : public SessionCommand {
 public:
  Serve(CLI::App& app, Common& common)
      : SessionCommand(
            app.add_subcommand(
                "serve",
                "Serve the interactive viewer (paper sec. 6.6, 6.7) in the browser: drag a target for a boxer, "
                "watch two boxers spar or a crowd of them; switch controllers and weights live "
                "(docs/viewer-protocol.md)."),
            common) {
    sub_->add_option("--policy", options_.policy,
                     "Policy bundle folder (default: the one mgrl train writes; none: the online search runs)");
    sub_->add_option("--host", options_.host,
                     "Address to listen on (other than 127.0.0.1: reachable from other machines)")
        ->default_str("127.0.0.1");
    sub_->add_option("--port", options_.port, "Port (0: any free one; the URL is printed)")->default_val(8080);
    sub_->add_flag("--open", options_.open, "Open the page in the desktop's browser (xdg-open)");
    sub_->add_option("--allow-origin", options_.allowOrigins,
                     "Also answer pages of this origin, e.g. http://mybox.lan:8080 (repeatable; by default only the "
                     "server's own address, localhost, 127.0.0.1 and [::1] at its port)");
    sub_->add_option("--sparring-scenario", options_.sparringScenario,
                     "Scenario whose behaviours play sparring and crowds (default: the scenario's sparring_scenario, "
                     "e.g. boxing.yaml's boxing_spar.yaml; none: the scenario's own behaviours)");
    sub_->add_option("--partner-policy", options_.partnerPolicy,
                     "Sparring and crowds: the second avatar of each pair plays this bundle (two policies spar; the "
                     "first plays the page's controller)");
    sub_->add_option("--partner-round", options_.partnerRound,
                     "With --partner-policy: the partner plays that self-play round's tables (mgrl train keeps every "
                     "round)")
        ->check(CLI::Range(1, 1000));
    sub_->add_option("--web", options_.web,
                     "The viewer's folder (default: MGRL_WEB, else share/mgrl/web beside an installed mgrl, else the "
                     "repository's web/)");
    addSessionOptions(options_, common, false);
  }

  void runSession(const Common& common) override {
    const std::string scenario = common.scenario;
    options_.announce = [scenario](const std::string& url) {
      std::cout << fmt::format("serving {} at {} (Ctrl-C stops)", scenario, url) << std::endl;
    };
    serve::runServe(options_);
  }

 private:
  serve::ServeCommandOptions options_;
};

class Stats final : public Command {
 public:
  Stats(CLI::App& app, Common& common)
      : Command(app.add_subcommand(
            "stats",
            "Report on bouts, real or synthesized (docs/stats.md): pelvis distance and facing "
            "distributions, effective and landed strikes per fighter-minute, planted-foot speed, root "
            "direction reversals, joint steps, interpenetration. BOUT: a folder of BVH files (one per "
            "fighter, one world frame; e.g. simulate --bvh-out's) or a quoted pattern such as "
            "'snu_martial_arts/motion/s_005_1_*.bvh'.")) {
    sub_->add_option("BOUT", options_.bouts,
                     "Bouts: folders or quoted file patterns (relative: the working folder, else the data folder)");
    sub_->add_flag("--snu", options_.snu, "Add every real SNU sparring bout (s_TTT_K_*.bvh grouped by TTT_K)");
    sub_->add_flag("--compare", options_.compare,
                   "Compare two groups: mgrl stats --compare REAL... -- SYNTH... (W1: Wasserstein-1 distance between "
                   "the pooled distributions)");
    StatsParams& p = options_.params;
    sub_->add_option("--land-radius", p.landRadius_m,
                     "A strike lands within this distance of the opponent's body capsules (m)")
        ->default_val(p.landRadius_m);
    sub_->add_option("--block-radius", p.blockRadius_m,
                     "A strike is blocked when it comes within this distance of an opponent's forearm (elbow to fist "
                     "tip) before it lands (m; 0: nothing blocks)")
        ->default_val(p.blockRadius_m);
    sub_->add_option("--close-distance", p.closeDistance_m, "Pelvises closer than this count as interpenetrating (m)")
        ->default_val(p.closeDistance_m);
    sub_->add_option("--reversal-min-speed", p.reversalMinSpeed_mps,
                     "Root steps slower than this are ignored by the reversal count (m/s)")
        ->default_val(p.reversalMinSpeed_mps);
    sub_->add_option("--punch-min-body-speed", p.annotation.punchMinBodySpeed_mps,
                     "Effective punch: the fist drives out from the body at this speed along the forearm, relative "
                     "to the pelvis, at one frame at least (m/s; 0: arm swings count too)")
        ->default_val(p.annotation.punchMinBodySpeed_mps);
    sub_->add_flag("--json", common.json, "Print one JSON object on stdout");
    addData(sub_, common.dataDir);
  }

  void run(const Common& common) override {
    if (common.dash && !options_.compare)
      throw Error("stats: expected --compare before a '--' (mgrl stats --compare REAL... -- SYNTH...)");
    if (options_.compare && !common.dash) throw Error("--compare: expected REAL... -- SYNTH..., found no '--'");
    for (const std::string& word : common.afterDash)
      if (word.size() > 1 && word[0] == '-')
        throw Error(fmt::format("--compare: expected options before '--', found '{}' after it", word));
    options_.synthetic = common.afterDash;
    options_.dataDir = dataDirectory(common.dataDir);
    options_.warn = warnLine;
    if (::isatty(2)) options_.log = logLine;  // progress only on a terminal
    const nlohmann::json report = runStats(options_);
    print(common, report, common.json ? std::string() : statsText(report));
  }

 private:
  StatsOptions options_;
};

class List final : public Command {
 public:
  List(CLI::App& app, Common& common)
      : Command(app.add_subcommand("list", "List every registered discretizer, reward, environment model and learner "
                                           "with its parameters, defaults and units.")) {
    sub_->add_flag("--json", common.json, "Print one JSON object on stdout");
  }

  void run(const Common& common) override {
    print(common, common.json ? listJson(plugins()) : nlohmann::json(), common.json ? std::string() : listText(plugins()));
  }
};

}  // namespace

std::unique_ptr<Command> serveCommand(CLI::App& app, Common& common) { return std::make_unique<Serve>(app, common); }
std::unique_ptr<Command> statsCommand(CLI::App& app, Common& common) { return std::make_unique<Stats>(app, common); }
std::unique_ptr<Command> listCommand(CLI::App& app, Common& common) { return std::make_unique<List>(app, common); }

}  // namespace mgrl::app::cli
