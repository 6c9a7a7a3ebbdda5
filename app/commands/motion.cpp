// `mgrl inspect`, `mgrl init` and `mgrl graph`: the capture and its motion graph.
#include <fmt/format.h>

#include "command.hpp"
#include "command_line.hpp"
#include "graph_command.hpp"
#include "inspect.hpp"
#include "mgrl/core/data_paths.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/starter/starter.hpp"
#include "plugins.hpp"

namespace mgrl::app::cli {
namespace {

LengthUnit unitsOption(const std::string& text) {
  try {
    return parseLengthUnit(text);
  } catch (const Error& e) {
    throw Error(fmt::format("--units: {}", e.what()));
  }
}

class Inspect final : public Command {
 public:
  Inspect(CLI::App& app, Common& common)
      : Command(app.add_subcommand("inspect", "Read motion files (.bvh, .amc) and report joints, frames, fps, "
                                              "duration, height, foot contacts and effective hits (paper sec. 6.2).")) {
    sub_->add_option("FILE", files_, "Motion files")->required();
    sub_->add_flag("--json", common.json, "Print one JSON object on stdout");
    sub_->add_option("--fps", options_.load.fps, "Resample to this frame rate before annotating");
    sub_->add_option("--units", units_, "Length units of the files: auto, m, cm, inch, cmu")->default_str("auto");
    sub_->add_option("--asf", asf_, "Skeleton for .amc files (default: <subject>.asf beside each)");
    sub_->add_option("--role", roles_, "Set a skeleton role, e.g. --role left_fist=LeftHand (repeatable)");
    sub_->add_option("--punch-min-speed", punchMinSpeed_,
                     "Effective punch: minimum fist speed along the forearm (m/s), or auto: chosen from each file's "
                     "own fist speeds")
        ->default_str(fmt::format("{}", options_.annotation.punchMinSpeed_mps));
    sub_->add_option("--punch-min-body-speed", options_.annotation.punchMinBodySpeed_mps,
                     "Effective punch: the fist drives out from the body at this speed along the forearm, relative "
                     "to the pelvis, at one frame at least (m/s; 0: arm swings count too)")
        ->default_val(options_.annotation.punchMinBodySpeed_mps);
    sub_->add_option("--swing-travel", options_.annotation.swingTravel_mps,
                     "Effective punch: not thrown while the body travels this fast over 3 s (walking or running arms), "
                     "unless the fist drives away from its shoulder (m/s; 0: off; mgrl init uses 0.9)")
        ->default_val(options_.annotation.swingTravel_mps);
  }

  void run(const Common& common) override {
    if (options_.load.fps < 0 || options_.load.fps > 10000)
      throw Error(fmt::format("--fps: expected a frame rate in (0, 10000], found {}", options_.load.fps));
    options_.load.units = unitsOption(units_);
    options_.load.asf = asf_;
    options_.load.warn = warnLine;
    options_.roles = parseRoles(roles_);
    if (!punchMinSpeed_.empty()) setPunchMinSpeed(punchMinSpeed_, options_.annotation);
    options_.annotation.validate();
    // Read everything first: on any error, stdout stays empty.
    std::vector<FileReport> reports;
    for (const std::string& file : files_) reports.push_back(inspectFile(file, options_));
    print(common, inspectJson(reports), common.json ? std::string() : inspectText(reports));
  }

 private:
  InspectOptions options_;
  std::string punchMinSpeed_;
  std::string units_ = "auto", asf_;
  std::vector<std::string> roles_, files_;
};

class Init final : public Command {
 public:
  Init(CLI::App& app, Common& common)
      : Command(app.add_subcommand(
            "init", "Start a scenario for your own motion files: inspect them, choose graph settings that keep most "
                    "frames, size the grids to the capture, pick behaviours it can do, write a commented scenario "
                    "and print the commands that build, train and view it (docs/own-capture.md).")) {
    sub_->add_option("FILE", files_, "Motion files (.bvh, .amc) of one skeleton")->required();
    sub_->add_option("--out", out_, "Scenario to write (default: NAME.yaml in the current folder)");
    sub_->add_option("--name", options_.name, "Scenario name (default: from the first file's name)");
    sub_->add_option("--data", data_,
                     "Data folder for relative paths (default: MGRL_DATA, else ~/.local/share/mgrl if it exists, else "
                     "../shared/mocap)");
    sub_->add_option("--fps", options_.fps, "Frame rate of the scenario")->default_val(options_.fps);
    sub_->add_option("--units", units_, "Length units of the files: auto, m, cm, inch, cmu")->default_str("auto");
    sub_->add_option("--role", roles_, "Set a skeleton role, e.g. --role left_fist=LeftHand (repeatable)");
    sub_->add_flag("--force", options_.force, "Replace an existing scenario file");
    sub_->add_flag("--json", common.json, "Print one JSON object on stdout");
  }

  void run(const Common& common) override {
    for (const std::string& file : files_) options_.files.emplace_back(file);
    options_.out = out_;
    options_.dataDir = dataDirectory(data_);
    options_.units = unitsOption(units_);
    options_.roles = parseRoles(roles_);
    options_.log = logLine;
    options_.plugins = &plugins();
    const nlohmann::json report = runInit(options_);
    print(common, report, common.json ? std::string() : initText(report));
  }

 private:
  InitOptions options_;
  std::vector<std::string> files_, roles_;
  std::string out_, units_ = "auto", data_;
};

class Graph final : public Command {
 public:
  Graph(CLI::App& app, Common& common)
      : Command(app.add_subcommand("graph", "Build a scenario's motion graph and state-action model (paper sec. 3, "
                                            "6.3), or reuse it from the cache, and report its size.")) {
    sub_->add_option("SCENARIO", common.scenario, "Scenario YAML file (see scenarios/README.md)")->required();
    sub_->add_flag("--json", common.json, "Print one JSON object on stdout");
    addDataAndCache(sub_, common.dataDir, common.cacheDir);
    sub_->add_flag("--no-cache", noCache_, "Rebuild even if a matching cached graph exists");
    sub_->add_option("--set", sets_, "Override a scenario key, e.g. --set graph.threshold=0.5 (repeatable)");
  }

  void run(const Common& common) override {
    const Scenario scenario = loadScenario(common.scenario, dataDirectory(common.dataDir), sets_);
    // The whole scenario, behaviours included, so that `graph` does not pass a file `train` refuses.
    checkBehaviors(scenario, plugins());
    GraphOptions options;
    options.cacheDir = common.cacheDir;
    options.noCache = noCache_;
    options.log = logLine;
    options.plugins = &plugins();
    GraphResult graph = obtainGraph(scenario, options);
    measurePlayback(graph, scenario.graph.blendFrames);
    print(common, graphJson(graph), common.json ? std::string() : graphText(graph));
  }

 private:
  bool noCache_ = false;
  std::vector<std::string> sets_;
};

}  // namespace

std::unique_ptr<Command> inspectCommand(CLI::App& app, Common& common) { return std::make_unique<Inspect>(app, common); }
std::unique_ptr<Command> initCommand(CLI::App& app, Common& common) { return std::make_unique<Init>(app, common); }
std::unique_ptr<Command> graphCommand(CLI::App& app, Common& common) { return std::make_unique<Graph>(app, common); }

}  // namespace mgrl::app::cli
