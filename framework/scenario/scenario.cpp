#include "mgrl/scenario/scenario.hpp"

#include <algorithm>
#include <system_error>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/data_paths.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/runtime/world.hpp"

namespace mgrl {

namespace {

// Bump when the graph construction changes what it computes, so old caches go stale.
// 2: no effective punch while knocked down; the fist falls back to the wrist's end site.
// 3: effective kicks; 4: kicks by the toe's whole speed; 5: root motion from the pelvis role,
// punches that drive the fist out from the body, heads in proportion; 6: a capture past
// GraphParams::kLibrarySeconds is bounded and cut where the performer stands still
constexpr int kGraphAlgorithmVersion = 6;

bool wildcardMatch(std::string_view pattern, std::string_view text) {
  // Iterative '*' / '?' matching with backtracking to the last star.
  std::size_t p = 0, t = 0, star = std::string_view::npos, mark = 0;
  while (t < text.size()) {
    if (p < pattern.size() && (pattern[p] == '?' || pattern[p] == text[t])) {
      ++p;
      ++t;
    } else if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      mark = t;
    } else if (star != std::string_view::npos) {
      p = star + 1;
      t = ++mark;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

// A `files:` entry: a path, or a pattern with * and ? in its file name; relative entries
// are looked up beside the scenario first, then in the data folder.
std::vector<std::filesystem::path> resolveFiles(const ConfigNode& entry, const std::filesystem::path& scenarioDir,
                                                const std::filesystem::path& dataDir) {
  const std::filesystem::path rel = entry.asString();
  if (rel.empty()) entry.fail("expected a file path, found an empty string");
  std::vector<std::filesystem::path> bases;
  if (rel.is_absolute()) bases.push_back("");
  else bases = {scenarioDir, dataDir};
  const std::string name = rel.filename().string();
  const bool pattern = name.find_first_of("*?") != std::string::npos;
  if (rel.parent_path().string().find_first_of("*?") != std::string::npos)
    entry.fail(fmt::format("expected wildcards only in the file name, found '{}'", rel.string()));
  for (const auto& base : bases) {
    const std::filesystem::path full = base.empty() ? rel : base / rel;
    std::error_code ec;
    if (!pattern) {
      if (std::filesystem::is_regular_file(full, ec)) return {full.lexically_normal()};
      continue;
    }
    std::vector<std::filesystem::path> found;
    const std::filesystem::path dir = full.parent_path();
    if (!std::filesystem::is_directory(dir, ec)) continue;
    for (const auto& item : std::filesystem::directory_iterator(dir, ec))
      if (item.is_regular_file(ec) && wildcardMatch(name, item.path().filename().string()))
        found.push_back(item.path().lexically_normal());
    if (!found.empty()) {
      std::sort(found.begin(), found.end());
      return found;
    }
  }
  entry.fail(fmt::format("expected a motion file or pattern matching files, found none for '{}' (looked in {} and "
                         "the data folder {})",
                         rel.string(), scenarioDir.string(), dataDir.string()));
}

MotionSpec readMotion(const ConfigNode& motion, const std::filesystem::path& scenarioDir,
                      const std::filesystem::path& dataDir) {
  motion.allowOnly({"files", "fps", "units", "asf", "roles", "annotation"});
  MotionSpec spec;
  if (!motion.has("files")) motion.fail("expected a 'files' list, found none");
  const ConfigNode files = motion.child("files");
  for (const ConfigNode& entry : files.elements())
    for (auto& file : resolveFiles(entry, scenarioDir, dataDir)) spec.files.push_back(std::move(file));
  if (spec.files.empty()) files.fail("expected at least one motion file, found an empty list");
  spec.fps = motion.number("fps", 30, 1, 1000);
  if (motion.has("units")) {
    const ConfigNode units = motion.child("units");
    spec.units = units.withLocation([&] { return parseLengthUnit(units.asString()); });
  }
  if (motion.has("asf")) {
    const ConfigNode asf = motion.child("asf");
    std::filesystem::path p = asf.asString();
    if (p.is_relative()) p = std::filesystem::exists(scenarioDir / p) ? scenarioDir / p : dataDir / p;
    spec.asf = p;
  }
  if (motion.has("roles")) {
    const ConfigNode roles = motion.child("roles");
    const std::vector<std::string> known = roleNames();
    for (const std::string& key : roles.keys()) {
      if (std::find(known.begin(), known.end(), key) == known.end())
        roles.child(key).fail(fmt::format("unknown role (expected one of: {})", fmt::join(known, ", ")));
      spec.roles[key] = roles.child(key).asString();
    }
  }
  if (motion.has("annotation")) {
    const ConfigNode a = motion.child("annotation");
    a.allowOnly({"contact_height_enter_m", "contact_height_exit_m", "contact_speed_enter_mps", "contact_speed_exit_mps",
                 "punch_min_speed_mps", "punch_min_alignment", "punch_max_speed_mps", "punch_min_body_speed_mps",
                 "swing_travel_mps", "swing_max_reach_mps", "knockdown_head_ratio", "kick_min_speed_mps",
                 "kick_min_alignment", "kick_min_height_m", "kick_max_speed_mps"});
    AnnotationParams& p = spec.annotation;
    p.contactHeightEnter_m = a.number("contact_height_enter_m", p.contactHeightEnter_m, 0, 1);
    p.contactHeightExit_m = a.number("contact_height_exit_m", p.contactHeightExit_m, 0, 1);
    p.contactSpeedEnter_mps = a.number("contact_speed_enter_mps", p.contactSpeedEnter_mps, 0, 10);
    p.contactSpeedExit_mps = a.number("contact_speed_exit_mps", p.contactSpeedExit_mps, 0, 10);
    // A speed, or `auto`: chosen from the capture's own fist speeds (autoPunchMinSpeed()).
    if (a.has("punch_min_speed_mps")) {
      const ConfigNode speed = a.child("punch_min_speed_mps");
      if (speed.yaml().IsScalar() && speed.yaml().Scalar() == "auto") {
        p.punchMinSpeedAuto = true;
      } else {
        try {
          p.punchMinSpeed_mps = speed.asNumber(0, 100);
        } catch (const ConfigError&) {
          speed.fail(fmt::format("expected a speed in [0, 100] m/s or auto, found '{}'",
                                 speed.yaml().IsScalar() ? speed.yaml().Scalar() : std::string("a list or map")));
        }
      }
    }
    p.punchMinAlignment = a.number("punch_min_alignment", p.punchMinAlignment, -1, 1);
    p.punchMaxSpeed_mps = a.number("punch_max_speed_mps", p.punchMaxSpeed_mps, 0, 1000);
    p.punchMinBodySpeed_mps = a.number("punch_min_body_speed_mps", p.punchMinBodySpeed_mps, 0, 100);
    p.swingTravel_mps = a.number("swing_travel_mps", p.swingTravel_mps, 0, 20);
    p.swingMaxReach_mps = a.number("swing_max_reach_mps", p.swingMaxReach_mps, 0, 100);
    p.knockdownHeadRatio = a.number("knockdown_head_ratio", p.knockdownHeadRatio, 0, 0.99);
    p.kickMinSpeed_mps = a.number("kick_min_speed_mps", p.kickMinSpeed_mps, 0, 100);
    p.kickMinAlignment = a.number("kick_min_alignment", p.kickMinAlignment, -1, 1);
    p.kickMinHeight_m = a.number("kick_min_height_m", p.kickMinHeight_m, 0, 3);
    p.kickMaxSpeed_mps = a.number("kick_max_speed_mps", p.kickMaxSpeed_mps, 0, 1000);
    a.withLocation([&] { p.validate(); });
  }
  return spec;
}

GraphParams readGraph(const ConfigNode& graph) {
  graph.allowOnly({"threshold", "velocity_weight", "root_height_weight", "contact_event", "local_minimum",
                   "blend_frames", "min_states", "joint_weights", "threads", "max_out_degree", "standing_cuts"});
  GraphParams p;
  p.threshold = graph.number("threshold", p.threshold, 1e-6, 10);
  p.velocityWeight = graph.number("velocity_weight", p.velocityWeight, 0, 10);
  p.rootHeightWeight = graph.number("root_height_weight", p.rootHeightWeight, 0, 100);
  if (graph.has("contact_event")) {
    const ConfigNode event = graph.child("contact_event");
    p.contactEvent = event.withLocation([&] { return parseContactEvent(event.asString()); });
  }
  p.localMinimum = graph.boolean("local_minimum", p.localMinimum);
  p.blendFrames = static_cast<int>(graph.integer("blend_frames", p.blendFrames, 0, 120));
  p.minStates = static_cast<int>(graph.integer("min_states", p.minStates, 1, 1000000));
  p.threads = static_cast<unsigned>(graph.integer("threads", 0, 0, 256));
  // `auto` (the default) leaves them unset: decided by the capture's length.
  auto isAuto = [](const ConfigNode& node) { return node.yaml().IsScalar() && node.yaml().Scalar() == "auto"; };
  if (graph.has("max_out_degree") && !isAuto(graph.child("max_out_degree"))) {
    const ConfigNode degree = graph.child("max_out_degree");
    const std::string found = degree.yaml().IsScalar() ? degree.yaml().Scalar() : std::string("a list or map");
    try {
      p.maxOutDegree = static_cast<int>(degree.asInteger(0, 100000));
    } catch (const ConfigError&) {
      p.maxOutDegree = 1;
    }
    if (*p.maxOutDegree == 1)
      degree.fail(fmt::format("expected auto, 0 (no bound) or an action count in [2, 100000], found '{}'", found));
  }
  if (graph.has("standing_cuts") && !isAuto(graph.child("standing_cuts")))
    p.standingCuts = graph.boolean("standing_cuts", false);
  if (graph.has("joint_weights")) {
    const ConfigNode weights = graph.child("joint_weights");
    for (const std::string& joint : weights.keys()) p.jointWeights[joint] = weights.child(joint).asNumber(0, 100);
  }
  return p;
}

std::vector<BehaviorSpec> readBehaviors(const ConfigNode& root) {
  std::vector<BehaviorSpec> result;
  if (!root.has("behaviors")) return result;
  const ConfigNode behaviors = root.section("behaviors");
  for (const std::string& name : behaviors.keys()) {
    const ConfigNode b = behaviors.child(name);
    if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") !=
                            std::string::npos)
      b.fail("expected a behaviour name of letters, digits, '_' and '-' (it names files of the policy bundle)");
    if (!b.isMap()) b.fail("expected a map with discretizer, reward and learner sections");
    b.allowOnly({"description", "weight", "activation", "stance", "discretizer", "reward", "environment", "learner",
                 "success"});
    BehaviorSpec spec{name,
                      b.string("description", ""),
                      b.number("weight", 1.0, -1e6, 1e6),
                      Activation::Always,
                      b,
                      b.section("discretizer"),
                      b.section("reward"),
                      b.child("environment"),
                      b.section("learner"),
                      b.child("success")};
    if (b.has("activation")) {
      const ConfigNode activation = b.child("activation");
      const std::string text = activation.asString();
      spec.activation = activation.withLocation([&] { return parseActivation(text); });
    }
    if (b.has("stance")) spec.stance = static_cast<int>(b.integer("stance", -1, 0, kMaxStances - 1));
    if (!spec.environment.isNull() && !spec.environment.isMap())
      spec.environment.fail("expected a map with 'type: static_target' or another environment model");
    result.push_back(std::move(spec));
  }
  // Stances number 0..N-1, each held by at least one behaviour.
  int stances = 0;
  for (const BehaviorSpec& spec : result) stances = std::max(stances, spec.stance + 1);
  for (int k = 0; k < stances; ++k)
    if (std::none_of(result.begin(), result.end(), [k](const BehaviorSpec& s) { return s.stance == k; })) {
      const auto last =
          std::find_if(result.begin(), result.end(), [&](const BehaviorSpec& s) { return s.stance == stances - 1; });
      last->node.child("stance").fail(fmt::format(
          "expected stances numbered 0..{} with a behaviour for each, found none for stance {}", stances - 1, k));
    }
  // A facing term that learns a stance (prefer: stance) belongs to a behaviour of that
  // stance, and cuts the real angles into as many parts as the scenario has stances: a copy
  // slip would otherwise train one stance's table for another.
  for (const BehaviorSpec& spec : result) {
    if (!spec.reward.isMap() || !spec.reward.has("terms") || !spec.reward.child("terms").yaml().IsSequence()) continue;
    for (const ConfigNode& term : spec.reward.child("terms").elements()) {
      if (!term.isMap() || term.string("term", "") != "facing" || term.string("prefer", "") != "stance") continue;
      const long long stance = term.integer("stance", 0, 0, kMaxStances - 1);
      const long long count = term.integer("stances", 3, 1, kMaxStances);
      if (spec.stance < 0)
        term.child("prefer").fail(
            "expected the behaviour to hold a stance (a `stance: k` key) for a facing term with prefer: stance, "
            "found none");
      if (stance != spec.stance)
        (term.has("stance") ? term.child("stance") : term.child("prefer"))
            .fail(fmt::format("expected the behaviour's stance, {}, found {}", spec.stance, stance));
      if (count != stances)
        (term.has("stances") ? term.child("stances") : term.child("prefer"))
            .fail(fmt::format("expected the scenario's number of stances, {}, found {}", stances, count));
    }
  }
  return result;
}

// `--set a.b.c=value`: walks (creating) maps down the dotted path and sets a scalar. A part
// may end in list indices, `terms[1]`, naming an element the file has (a list is not
// made or grown from the command line): `behaviors.keep.reward.terms[1].weight=0.5`.
void applyOverride(YAML::Node root, const std::string& text, const std::string& source) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ConfigError(fmt::format("{}: --set {}: expected KEY=VALUE with a dotted KEY such as "
                                  "behaviors.hit.learner.budget",
                                  source, quoteToken(text)));
  const std::string key = text.substr(0, eq), value = text.substr(eq + 1);
  std::vector<std::string> parts;
  for (std::size_t begin = 0;;) {
    const std::size_t dot = key.find('.', begin);
    parts.push_back(key.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin));
    if (dot == std::string::npos) break;
    begin = dot + 1;
  }
  std::vector<YAML::Node> chain{root};
  for (std::size_t i = 0; i < parts.size(); ++i) {
    // "name[2][0]": the name, then its indices.
    std::string name = parts[i];
    std::vector<std::size_t> indices;
    if (const std::size_t open = name.find('['); open != std::string::npos) {
      std::string rest = name.substr(open);
      name.resize(open);
      while (!rest.empty()) {
        const std::size_t close = rest.find(']');
        const std::string digits = close == std::string::npos ? std::string() : rest.substr(1, close - 1);
        if (rest.front() != '[' || digits.empty() || digits.size() > 6 ||
            digits.find_first_not_of("0123456789") != std::string::npos)
          throw ConfigError(fmt::format("{}: --set {}: expected a list index such as terms[0], found {}", source, key,
                                        quoteToken(parts[i])));
        indices.push_back(static_cast<std::size_t>(std::stoul(digits)));
        rest.erase(0, close + 1);
      }
    }
    if (name.empty())
      throw ConfigError(fmt::format("{}: --set {}: expected a dotted key without empty parts", source, key));
    const std::string before = fmt::format("{}", fmt::join(parts.begin(), parts.begin() + static_cast<long>(i), "."));
    YAML::Node& here = chain.back();
    if (here.IsDefined() && !here.IsMap() && !here.IsNull())
      throw ConfigError(fmt::format("{}: --set {}: expected '{}' to be a map, found {}", source, key, before,
                                    here.IsSequence() ? "a list (name an element: KEY[0])" : "a value"));
    const bool last = i + 1 == parts.size();
    if (last && indices.empty()) {
      // A plugin block switched to another type starts afresh: the file's other keys
      // were that type's parameters.
      if (name == "type" && here.IsMap() && here["type"].IsScalar() && here["type"].Scalar() != value)
        here = YAML::Node(YAML::NodeType::Map);
      here[name] = value;
      continue;
    }
    YAML::Node node = here[name];
    std::string path = before.empty() ? name : before + "." + name;
    for (std::size_t k = 0; k < indices.size(); ++k) {
      if (!node.IsSequence())
        throw ConfigError(fmt::format("{}: --set {}: expected '{}' to be a list, found {}", source, key, path,
                                      node.IsDefined() && !node.IsNull() ? "a map or a value" : "nothing"));
      if (indices[k] >= node.size())
        throw ConfigError(fmt::format("{}: --set {}: expected an index below {} ('{}' has {} element{}), found {}",
                                      source, key, node.size(), path, node.size(), node.size() == 1 ? "" : "s",
                                      indices[k]));
      path += fmt::format("[{}]", indices[k]);
      if (last && k + 1 == indices.size()) {
        node[indices[k]] = value;
        break;
      }
      node.reset(node[indices[k]]);  // rebinds; `node = ...` would overwrite the element
    }
    if (!last) chain.push_back(node);
  }
}

// A scenario's name names its cache entries (<cache>/graphs/<name>-<hash>): a safe word
// (`../../x` wrote outside the cache, `a/b` made folders, a 10 MB name failed
// as a "damaged cache", a name that is not UTF-8 was silently not cached).
std::string scenarioName(const ConfigNode& root, const std::filesystem::path& source) {
  constexpr std::size_t kMaxName = 64;
  auto safe = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
           c == '.';
  };
  if (root.has("name")) {
    const ConfigNode node = root.child("name");
    const std::string name = node.asString();
    if (name.empty() || name.size() > kMaxName || name.front() == '.' ||
        !std::all_of(name.begin(), name.end(), safe))
      node.fail(fmt::format("expected a name of 1 to {} letters, digits, '_', '-' or '.' (not first), found {}",
                            kMaxName, quoteToken(name)));
    return name;
  }
  // From the file's name: unsafe characters become '_'.
  std::string name = source.stem().string().substr(0, kMaxName);
  for (char& c : name)
    if (!safe(c)) c = '_';
  if (name.empty() || name.front() == '.') name.insert(name.begin(), 's');
  return name;
}

// `sparring_scenario:` names another scenario file, relative to this one's folder (or
// absolute). Only `mgrl serve` opens it (checkSparringScenario()): a scenario copied
// elsewhere without it still builds, trains and simulates.
std::filesystem::path sparringScenarioPath(const ConfigNode& node, const std::filesystem::path& dir) {
  const std::string text = node.asString();
  if (text.empty()) node.fail("expected a scenario file (relative to this scenario's folder), found an empty string");
  return std::filesystem::path(text).is_absolute() ? std::filesystem::path(text) : dir / text;
}

}  // namespace

Scenario parseScenario(std::string_view text, const std::filesystem::path& source,
                       const std::filesystem::path& dataDir, const std::vector<std::string>& overrides) {
  ConfigNode root = ConfigNode::parse(text, source.string());
  if (!root.isMap()) root.fail("expected a scenario (a map with 'motion' and 'graph' sections), found something else");
  // Type switches first: they reset their block, which must not swallow other overrides.
  auto switchesType = [](const std::string& o) {
    const std::string key = o.substr(0, o.find('='));
    return key == "type" || (key.size() > 5 && key.compare(key.size() - 5, 5, ".type") == 0);
  };
  for (const std::string& o : overrides)
    if (switchesType(o)) applyOverride(root.yaml(), o, source.string());
  for (const std::string& o : overrides)
    if (!switchesType(o)) applyOverride(root.yaml(), o, source.string());
  for (const std::string& o : overrides) root.noteOverride(o.substr(0, o.find('=')), "--set " + o);
  root.allowOnly({"name", "description", "motion", "graph", "behaviors", "world", "sparring_scenario"});
  // The world section is read where a world is made (readWorldParams(worldNode(s))); it
  // is checked here so that a mistake in it fails every command at once.
  if (root.has("world")) readWorldParams(root.child("world"));
  const std::filesystem::path dir = source.parent_path().empty() ? std::filesystem::path(".") : source.parent_path();
  Scenario s{source,
             scenarioName(root, source),
             root.string("description", ""),
             readMotion(root.section("motion"), dir, dataDir),
             readGraph(root.section("graph")),
             readBehaviors(root),
             root};
  if (root.has("sparring_scenario")) s.sparringScenario = sparringScenarioPath(root.child("sparring_scenario"), dir);
  recordScenarioDataDirectory(dataDir);
  return s;
}

void checkSparringScenario(const Scenario& s) {
  if (s.sparringScenario.empty()) return;
  const ConfigNode node = s.root.child("sparring_scenario");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(s.sparringScenario, ec))
    node.fail(fmt::format("expected a scenario file (relative to this scenario's folder), found \"{}\" (no file at {})",
                          node.asString(), s.sparringScenario.string()));
  if (std::filesystem::equivalent(s.sparringScenario, s.path, ec))
    node.fail("expected another scenario than this one (its behaviours spar already), found this file");
}

Scenario loadScenario(const std::filesystem::path& path, const std::filesystem::path& dataDir,
                      const std::vector<std::string>& overrides) {
  return parseScenario(readFile(path), path, dataDir, overrides);
}

std::string graphCacheKey(const Scenario& s) {
  Hasher h;
  h.update(std::string_view("mgrl.graph"));
  h.update(std::int64_t{kGraphAlgorithmVersion});
  const MotionSpec& m = s.motion;
  h.update(std::int64_t(m.files.size()));
  for (const auto& file : m.files) {
    h.update(std::string_view(file.filename().string()));
    hashFileContents(h, file);
  }
  if (!m.asf.empty()) hashFileContents(h, m.asf);
  else {
    // AMC files take <subject>.asf from beside them: hash those too.
    for (const auto& file : m.files)
      if (file.extension() == ".amc" || file.extension() == ".AMC") hashFileContents(h, defaultAsfFor(file));
  }
  h.update(m.fps);
  h.update(std::int64_t(m.units));
  h.update(std::int64_t(m.roles.size()));
  for (const auto& [role, joint] : m.roles) {
    h.update(std::string_view(role));
    h.update(std::string_view(joint));
  }
  const AnnotationParams& a = m.annotation;
  for (double v : {a.contactHeightEnter_m, a.contactHeightExit_m, a.contactSpeedEnter_mps, a.contactSpeedExit_mps,
                   a.punchMinSpeed_mps, a.punchMinAlignment, a.punchMaxSpeed_mps, a.punchMinBodySpeed_mps, a.knockdownHeadRatio,
                   a.kickMinSpeed_mps, a.kickMinAlignment, a.kickMinHeight_m, a.kickMaxSpeed_mps})
    h.update(v);
  // Only when set, so that every other scenario keeps its key.
  if (a.punchMinSpeedAuto) h.update(std::string_view("punch_min_speed_mps=auto"));
  if (a.swingTravel_mps > 0) {
    h.update(std::string_view("swing_travel_mps"));
    h.update(a.swingTravel_mps);
    h.update(a.swingMaxReach_mps);
  }
  const GraphParams& g = s.graph;
  for (double v : {g.threshold, g.velocityWeight, g.rootHeightWeight}) h.update(v);
  h.update(std::int64_t(g.contactEvent));
  h.update(std::int64_t(g.localMinimum));
  h.update(std::int64_t(g.blendFrames));
  h.update(std::int64_t(g.minStates));
  h.update(std::int64_t(g.jointWeights.size()));
  for (const auto& [joint, weight] : g.jointWeights) {
    h.update(std::string_view(joint));
    h.update(weight);
  }
  // Only when set (`auto` follows from the capture, which is hashed above).
  if (g.maxOutDegree) {
    h.update(std::string_view("max_out_degree"));
    h.update(std::int64_t(*g.maxOutDegree));
  }
  if (g.standingCuts) {
    h.update(std::string_view("standing_cuts"));
    h.update(std::int64_t(*g.standingCuts));
  }
  return h.hex();
}

}  // namespace mgrl
