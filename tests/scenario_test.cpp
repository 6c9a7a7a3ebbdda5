// Scenario YAML: strict keys, types, ranges, paths; and the graph cache in use.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "builtin_plugins.hpp"
#include "graph_command.hpp"
#include "mgrl/core/data_paths.hpp"
#include "mgrl/graph/graph_cache.hpp"
#include "mgrl/motion/motion_database.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace scenario_test {

using namespace mgrl;
using Catch::Contains;

namespace {

const std::filesystem::path kSource = std::filesystem::path(MGRL_SOURCE_DIR) / "scenarios" / "test.yaml";

Scenario parse(const std::string& text) { return parseScenario(text, kSource, test::mocap()); }

const char* kGood = R"(name: mini
motion:
  files: [cmu/bvh/13_17_boxing.bvh]
  fps: 30
graph:
  threshold: 0.4
)";

}  // namespace

TEST_CASE("both shipped scenarios load", "[scenario][data]") {
  for (const char* name : {"boxing", "sparring"}) {
    CAPTURE(name);
    const Scenario s =
        loadScenario(std::filesystem::path(MGRL_SOURCE_DIR) / "scenarios" / (std::string(name) + ".yaml"), test::mocap());
    CHECK(s.name == name);
    CHECK(s.motion.fps == 30);
    CHECK(!s.motion.files.empty());
  }
}

TEST_CASE("a scenario resolves files in the data folder and expands patterns in order", "[scenario][data]") {
  const Scenario s = parse("motion:\n  files: [snu_martial_arts/motion/s_005_*.bvh, cmu/bvh/13_18_boxing.bvh]\ngraph: {}\n");
  REQUIRE(s.motion.files.size() == 5);
  CHECK(s.motion.files[0].filename() == "s_005_1_1.bvh");
  CHECK(s.motion.files[3].filename() == "s_005_3_2.bvh");
  CHECK(s.motion.files[4].filename() == "13_18_boxing.bvh");
  CHECK(s.name == "test");
  CHECK(s.graph.threshold == GraphParams{}.threshold);
}

TEST_CASE("scenario mistakes name the file, line, column and key", "[scenario]") {
  REQUIRE_NOTHROW(parse(kGood));
  SECTION("unknown key") {
    REQUIRE_THROWS_WITH(parse(std::string(kGood) + "  treshold: 0.2\n"),
                        Contains("test.yaml:7:13: graph.treshold: unknown key (expected one of: threshold,"));
  }
  SECTION("unknown top-level key") {
    REQUIRE_THROWS_WITH(parse(std::string(kGood) + "grpah: {}\n"), Contains("test.yaml:7:8: grpah: unknown key"));
  }
  SECTION("wrong type") {
    REQUIRE_THROWS_WITH(parse("motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\ngraph:\n  threshold: high\n"),
                        Contains("test.yaml:4:14: graph.threshold: expected a number in [1e-06, 10], found 'high'"));
  }
  SECTION("out of range") {
    REQUIRE_THROWS_WITH(parse("motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\n  fps: 0\ngraph: {}\n"),
                        Contains("test.yaml:3:8: motion.fps: expected a number in [1, 1000], found 0"));
    REQUIRE_THROWS_WITH(parse("motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\ngraph:\n  blend_frames: 2.5\n"),
                        Contains("graph.blend_frames: expected a whole number in [0, 120], found '2.5'"));
  }
  SECTION("missing section") {
    REQUIRE_THROWS_WITH(parse("motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\n"),
                        Contains("test.yaml:1:1: expected a 'graph' section, found none"));
    REQUIRE_THROWS_WITH(parse("graph: {}\n"), Contains("expected a 'motion' section, found none"));
  }
  SECTION("no motion files") {
    REQUIRE_THROWS_WITH(parse("motion:\n  files: []\ngraph: {}\n"),
                        Contains("motion.files: expected at least one motion file, found an empty list"));
    REQUIRE_THROWS_WITH(parse("motion:\n  fps: 30\ngraph: {}\n"), Contains("motion: expected a 'files' list, found none"));
  }
  SECTION("a file or pattern that matches nothing") {
    REQUIRE_THROWS_WITH(parse("motion:\n  files: [cmu/bvh/nothing_*.bvh]\ngraph: {}\n"),
                        Contains("test.yaml:2:11: motion.files[0]: expected a motion file or pattern matching files, "
                                 "found none for 'cmu/bvh/nothing_*.bvh'"));
  }
  SECTION("a library's graph settings") {
    CHECK_FALSE(parse(kGood).graph.maxOutDegree);
    CHECK_FALSE(parse(kGood).graph.standingCuts);
    CHECK_FALSE(parse(std::string(kGood) + "  max_out_degree: auto\n  standing_cuts: auto\n").graph.maxOutDegree);
    const Scenario set = parse(std::string(kGood) + "  max_out_degree: 24\n  standing_cuts: true\n");
    CHECK(set.graph.maxOutDegree == 24);
    CHECK(set.graph.standingCuts == true);
    CHECK(parse(std::string(kGood) + "  max_out_degree: 0\n").graph.maxOutDegree == 0);
    REQUIRE_THROWS_WITH(parse(std::string(kGood) + "  max_out_degree: 1\n"),
                        Contains("test.yaml:7:19: graph.max_out_degree: expected auto, 0 (no bound) or an action count "
                                 "in [2, 100000], found '1'"));
    REQUIRE_THROWS_WITH(parse(std::string(kGood) + "  max_out_degree: many\n"),
                        Contains("graph.max_out_degree: expected auto, 0 (no bound) or an action count in [2, 100000], "
                                 "found 'many'"));
    REQUIRE_THROWS_WITH(parse(std::string(kGood) + "  standing_cuts: sometimes\n"),
                        Contains("graph.standing_cuts: expected"));
    // Set, they are part of the graph's cache key; `auto` is not (the capture decides it).
    CHECK(graphCacheKey(parse(std::string(kGood) + "  max_out_degree: auto\n")) == graphCacheKey(parse(kGood)));
    CHECK(graphCacheKey(parse(std::string(kGood) + "  max_out_degree: 24\n")) != graphCacheKey(parse(kGood)));
    CHECK(graphCacheKey(parse(std::string(kGood) + "  standing_cuts: false\n")) != graphCacheKey(parse(kGood)));
  }
  SECTION("bad enumerations") {
    REQUIRE_THROWS_WITH(parse(std::string(kGood) + "  contact_event: right_foot\n"),
                        Contains("graph.contact_event: expected one of left_foot_liftoff, any_contact_change, none, "
                                 "found 'right_foot'"));
    REQUIRE_THROWS_WITH(parse("motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\n  units: feet\ngraph: {}\n"),
                        Contains("motion.units:"));
    REQUIRE_THROWS_WITH(parse("motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\n  roles: {left_paw: X}\ngraph: {}\n"),
                        Contains("motion.roles.left_paw: unknown role"));
  }
  SECTION("wrong shapes") {
    REQUIRE_THROWS_WITH(parse("motion:\n  files: cmu/bvh/13_17_boxing.bvh\ngraph: {}\n"),
                        Contains("test.yaml:2:10: motion.files: expected a list, found 'cmu/bvh/13_17_boxing.bvh'"));
    REQUIRE_THROWS_WITH(parse("motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\ngraph: 3\n"),
                        Contains("test.yaml:3:8: graph: expected a map, found '3'"));
    REQUIRE_THROWS_WITH(parse(std::string(kGood) + "  local_minimum: maybe\n"),
                        Contains("graph.local_minimum: expected true or false, found 'maybe'"));
    REQUIRE_THROWS_WITH(parse(std::string(kGood) + "  joint_weights: {LeftHand: heavy}\n"),
                        Contains("graph.joint_weights.LeftHand: expected a number in [0, 100], found 'heavy'"));
    REQUIRE_THROWS_WITH(parse(std::string(kGood) + "  joint_weights: {[a, b]: 1}\n"),
                        Contains("graph.joint_weights: expected a plain key, found a map or list as key"));
  }
  SECTION("bad file entries") {
    REQUIRE_THROWS_WITH(parse("motion:\n  files: [cmu/*/13_17_boxing.bvh]\ngraph: {}\n"),
                        Contains("motion.files[0]: expected wildcards only in the file name, found "
                                 "'cmu/*/13_17_boxing.bvh'"));
    REQUIRE_THROWS_WITH(parse("motion:\n  files: ['']\ngraph: {}\n"),
                        Contains("motion.files[0]: expected a file path, found an empty string"));
  }
  SECTION("annotation thresholds that contradict each other") {
    REQUIRE_THROWS_WITH(
        parse("motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\n  annotation:\n    contact_height_enter_m: 0.2\ngraph: {}\n"),
        Contains("test.yaml:4:5: motion.annotation: annotation: expected exit thresholds at least the enter thresholds"));
  }
  SECTION("a punch threshold that is neither a speed nor auto") {
    REQUIRE_THROWS_WITH(
        parse("motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\n  annotation:\n    punch_min_speed_mps: fast\ngraph: {}\n"),
        Contains("test.yaml:4:26: motion.annotation.punch_min_speed_mps: expected a speed in [0, 100] m/s or auto, found "
                 "'fast'"));
    REQUIRE_THROWS_WITH(
        parse("motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\n  annotation:\n    punch_min_speed_mps: [2]\ngraph: {}\n"),
        Contains("punch_min_speed_mps: expected a speed in [0, 100] m/s or auto, found 'a list or map'"));
  }
  SECTION("malformed YAML") {
    REQUIRE_THROWS_WITH(parse("motion: [\n"), Contains("test.yaml:2:1: expected valid YAML, found a syntax error"));
    REQUIRE_THROWS_WITH(parse("- just\n- a list\n"), Contains("expected a scenario"));
  }
}

TEST_CASE("the graph cache is reused, refreshed when inputs change and rebuilt when damaged", "[scenario][graph_cache][data]") {
  const auto cache = std::filesystem::temp_directory_path() / "mgrl_cache_test";
  std::filesystem::remove_all(cache);
  Scenario s = parse(kGood);
  std::vector<std::string> log;
  mgrl::GraphOptions options;
  options.plugins = &mgrl::builtinPlugins();
  options.cacheDir = cache;
  options.log = [&](const std::string& m) { log.push_back(m); };

  const mgrl::GraphResult first = mgrl::obtainGraph(s, options);
  CHECK_FALSE(first.fromCache);
  REQUIRE(std::filesystem::exists(first.bundle / "manifest.json"));
  const mgrl::GraphResult second = mgrl::obtainGraph(s, options);
  CHECK(second.fromCache);
  CHECK(second.model.actionFrames == first.model.actionFrames);
  CHECK(second.model.frameRoot == first.model.frameRoot);

  SECTION("--no-cache rebuilds") {
    options.noCache = true;
    CHECK_FALSE(mgrl::obtainGraph(s, options).fromCache);
  }
  SECTION("a changed parameter makes the bundle stale") {
    s.graph.threshold = 0.35;
    const mgrl::GraphResult third = mgrl::obtainGraph(s, options);
    CHECK_FALSE(third.fromCache);
    CHECK(log.back().find("saved") != std::string::npos);
    CHECK(std::any_of(log.begin(), log.end(), [](const std::string& m) { return m.find("stale") != std::string::npos; }));
    CHECK(mgrl::obtainGraph(s, options).fromCache);
  }
  SECTION("a damaged array is detected and rebuilt") {
    const auto file = first.bundle / "action_frames.npy";
    std::string bytes = readFile(file);
    bytes[bytes.size() - 3] ^= 0x5a;
    writeFileAtomically(file, bytes);
    const mgrl::GraphResult third = mgrl::obtainGraph(s, options);
    CHECK_FALSE(third.fromCache);
    CHECK(std::any_of(log.begin(), log.end(), [](const std::string& m) { return m.find("damaged") != std::string::npos; }));
    CHECK(third.model.actionFrames == first.model.actionFrames);
    CHECK(mgrl::obtainGraph(s, options).fromCache);
  }
  SECTION("a garbage manifest is detected and rebuilt") {
    writeFileAtomically(first.bundle / "manifest.json", "{ not json");
    CHECK_FALSE(mgrl::obtainGraph(s, options).fromCache);
  }
  std::filesystem::remove_all(cache);
}

// A scenario's name becomes a cache folder's name, so it must be a safe word;
// the error shows a bounded excerpt, never the whole name.
TEST_CASE("a scenario name is a safe word of bounded length", "[scenario][errors]") {
  const std::string body = "motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\ngraph: {}\n";
  for (const std::string& name : {std::string("../../../../../tmp/x"), std::string("a/b/c"), std::string(".hidden"),
                                   std::string(200, 'n'), std::string("caf\xc3\xa9")}) {
    CAPTURE(name);
    try {
      parse("name: \"" + name + "\"\n" + body);
      FAIL("expected a refusal");
    } catch (const ConfigError& e) {
      const std::string what = e.what();
      CHECK_THAT(what, Contains("test.yaml:1:7: name: expected a name of 1 to 64 letters, digits, '_', '-' or "
                                  "'.' (not first), found '"));
      CHECK(what.size() < 200);
    }
  }
  // Not UTF-8 at all (accepted, then the cache was silently not written).
  CHECK_THROWS_AS(parse("name: bad\xff\xfe\n" + body), ConfigError);
  CHECK(parse("name: boxing-v2.1\n" + body).name == "boxing-v2.1");
  // Without a name, the file's stem, made safe.
  CHECK(parseScenario(body, std::filesystem::path("/tmp/my scenario (1).yaml"), test::mocap()).name ==
        "my_scenario__1_");
}

TEST_CASE("punch_min_speed_mps: auto reaches the annotation and the graph cache key, and the database says what it chose",
          "[scenario][data]") {
  const std::string text = "motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\n  fps: 30\n  annotation:\n"
                           "    punch_min_speed_mps: auto\ngraph:\n  threshold: 0.4\n";
  const Scenario automatic = parse(text);
  CHECK(automatic.motion.annotation.punchMinSpeedAuto);
  const Scenario given = parse(kGood);
  CHECK_FALSE(given.motion.annotation.punchMinSpeedAuto);
  // The same scenario with a threshold given has another graph: another cache key.
  CHECK(graphCacheKey(automatic) != graphCacheKey(given));
  const MotionDatabase db = loadMotionDatabase(automatic.motion);
  REQUIRE(db.autoPunchSpeed.has_value());
  CHECK(db.autoPunchSpeed->samples >= 300);
  CHECK(db.autoPunchSpeed->speed_mps > 1.5);
  CHECK(db.autoPunchSpeed->speed_mps < 2.3);
  // Every clip was annotated at the chosen speed: as many hits as annotate() at that speed.
  AnnotationParams at = automatic.motion.annotation;
  at.punchMinSpeedAuto = false;
  at.punchMinSpeed_mps = db.autoPunchSpeed->speed_mps;
  CHECK(db.clips[0].annotation.hits.size() == annotate(db.clips[0].motion, db.roles, at).hits.size());
  CHECK_FALSE(loadMotionDatabase(given.motion).autoPunchSpeed.has_value());
}

TEST_CASE("the data folder is --data, else MGRL_DATA, else the user's data folder once it exists, else the checkout's",
          "[scenario][data]") {
  // The variables this test changes, put back as they were when it ends.
  struct Saved {
    std::string name;
    std::optional<std::string> value;
  };
  std::vector<Saved> saved;
  for (const char* name : {"MGRL_DATA", "XDG_DATA_HOME", "HOME"}) {
    const char* v = std::getenv(name);
    saved.push_back({name, v ? std::optional<std::string>(v) : std::nullopt});
  }
  struct Restore {
    std::vector<Saved>& saved;
    ~Restore() {
      for (const Saved& s : saved) s.value ? ::setenv(s.name.c_str(), s.value->c_str(), 1) : ::unsetenv(s.name.c_str());
    }
  } restore{saved};
  const std::filesystem::path checkout =
      std::filesystem::path(test::sourceDirectory()).parent_path() / "shared" / "mocap";
  test::TempDir temp("data-folder");
  ::unsetenv("MGRL_DATA");
  ::setenv("XDG_DATA_HOME", temp.path.c_str(), 1);
  CHECK(userDataDirectory() == temp.path / "mgrl");
  CHECK(dataDirectory() == checkout);  // the user's folder does not exist yet
  std::filesystem::create_directories(temp.path / "mgrl");
  CHECK(dataDirectory() == temp.path / "mgrl");
  ::setenv("MGRL_DATA", "/elsewhere", 1);
  CHECK(dataDirectory() == "/elsewhere");
  CHECK(dataDirectory("given") == "given");
  ::unsetenv("MGRL_DATA");
  ::unsetenv("XDG_DATA_HOME");
  ::setenv("HOME", temp.path.c_str(), 1);
  CHECK(userDataDirectory() == temp.path / ".local" / "share" / "mgrl");
  CHECK(dataDirectory() == checkout);
}

}  // namespace scenario_test
