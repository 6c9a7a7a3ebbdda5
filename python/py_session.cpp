// mgrl.Session's members (session.hpp): problems as NumPy arrays, C++ training, eval's
// trials, the world run headless and policy bundles for NumPy tables.
#include "session.hpp"

namespace mgrl::python {

std::filesystem::path shippedScenario(const std::filesystem::path& scenario) {
  std::error_code error;
  if (scenario.has_parent_path() || std::filesystem::exists(scenario, error)) return scenario;
  const py::module_ mgrl = py::module_::import("mgrl");
  try {
    return mgrl.attr("scenario_path")(scenario.string()).cast<std::string>();
  } catch (const py::error_already_set&) {
    std::vector<std::string> names;
    for (const py::handle name : mgrl.attr("scenarios")()) {
      const std::string file = name.cast<std::string>();
      names.push_back(file.substr(0, file.size() - std::string_view(".yaml").size()));
    }
    throw Error(
        fmt::format("scenario: expected a scenario file or the name of one the module carries ({}), found "
                    "'{}': no such file in {} and no such name",
                    fmt::join(names, ", "), scenario.string(), std::filesystem::current_path(error).string()));
  }
}

std::string setsMessage(const std::string& what) {
  constexpr std::string_view flag = "--set ";
  const std::size_t colon = what.find(": ");
  if (what.rfind(flag, 0) != 0 || colon == std::string::npos) return what;
  const std::string set = what.substr(flag.size(), colon - flag.size());
  const std::size_t eq = set.find('=');
  if (eq == std::string::npos) return what;
  return fmt::format("sets['{}'] (= {}){}", set.substr(0, eq), set.substr(eq + 1), what.substr(colon));
}

std::unique_ptr<Learner> learnerFrom(const nlohmann::json& config, const std::string& behavior) {
  const std::string type = config.value("type", std::string());
  if (!type.empty() && !builtinPlugins().learners.find(type))
    throw Error(fmt::format("learner: expected a registered learner ({}), found '{}'",
                            builtinPlugins().learners.describeKnown(), type));
  const std::string source = fmt::format("{} learner", behavior);
  try {
    return builtinPlugins().learners.create(ConfigNode::parse(config.dump(), source));
  } catch (const Error& e) {
    // "SOURCE:LINE:COLUMN: KEY: problem" -> "sets['KEY']: problem"
    const std::string what = e.what();
    const std::size_t at = what.rfind(source, 0) == 0 ? what.find(": ") : std::string::npos;
    if (at == std::string::npos) throw;
    const std::string rest = what.substr(at + 2);
    const std::size_t key = rest.find(": ");
    if (key == std::string::npos) throw Error(fmt::format("sets: {}", rest));
    throw Error(fmt::format("sets['{}']: {}", rest.substr(0, key), rest.substr(key + 2)));
  }
}

PySession::PySession(const std::filesystem::path& scenario, const py::object& data, const py::object& cache,
                     const py::object& sets, const py::object& policy) {
  SessionOptions options;
  options.scenario = shippedScenario(scenario);
  if (!data.is_none()) options.dataDir = data.cast<std::filesystem::path>();
  if (!cache.is_none()) options.cacheDir = cache.cast<std::filesystem::path>();
  options.sets = setsOf(sets);
  options.log = toStderr;
  options.plugins = &builtinPlugins();
  SessionNeeds needs;
  needs.motion = false;  // the model is what Python works on; a cached graph starts fast
  std::filesystem::path policyDir;
  if (!policy.is_none()) policyDir = policy.cast<std::filesystem::path>();
  py::gil_scoped_release release;
  try {
    session_ = openSession(options, needs);
  } catch (const Error& e) {
    throw Error(setsMessage(e.what()));
  }
  if (!policyDir.empty()) {
    bundle_ = std::make_unique<PolicyBundle>(readBundle(policyDir, "policy"));
    policyDir_ = policyDir;
  }
}

std::vector<std::string> PySession::behaviorNames() const {
  std::vector<std::string> names;
  for (const Behavior& b : session_->behaviors) names.push_back(b.name);
  return names;
}

const Behavior& PySession::behavior(const std::string& name) const {
  for (const Behavior& b : session_->behaviors)
    if (b.name == name) return b;
  throw Error(fmt::format("behavior: expected one of the scenario's behaviours ({}), found '{}'",
                          fmt::join(behaviorNames(), ", "), name));
}

ProblemArrays PySession::problem(const std::string& name) const {
  const Behavior& b = behavior(name);
  const Discretizer& grid = *b.discretizer;
  // Speed layers fit the formula as they are: a backup lands exactly on its layer, so a
  // cell's corners are those of one layer. A kd-tree's hanging vertices do not: their
  // rows are interpolated from other vertices after each backup, not backed up.
  if (!grid.hanging().empty())
    throw Error(
        fmt::format("problem({}): its grid ({}) has {} hanging vertices, whose values are interpolated, "
                    "not backed up; only grids without them are offered to Python yet",
                    name, grid.type(), grid.hanging().size()));
  const StateActionModel& model = session_->model();
  const Problem problem = b.problem(model);
  GridModel g;
  const auto started = std::chrono::steady_clock::now();
  {
    py::gil_scoped_release release;
    g = GridModel::build(problem, std::max(1u, std::thread::hardware_concurrency()));
  }
  const double tabulated = since(started);
  const std::size_t A = g.actionCount, V = g.vertexCount, K = std::size_t{1} << g.dimension;
  ProblemArrays p;
  p.behavior = name;
  p.states = model.stateCount();
  p.actions = A;
  p.vertexCount = V;
  p.dimension = g.dimension;
  p.rewards = py::array_t<float>({A, V});
  p.corners = py::array_t<std::int32_t>({A, V, K});
  p.weights = py::array_t<float>({A, V, K});
  float* r = p.rewards.mutable_data();
  std::int32_t* c = p.corners.mutable_data();
  float* w = p.weights.mutable_data();
  // Filled on every core, an action at a time (each writes its own rows); the GIL is
  // released: the arrays are not yet visible to Python.
  {
    py::gil_scoped_release release;
    parallelFor(A, std::max(1u, std::thread::hardware_concurrency()), [&](std::size_t a, unsigned) {
      for (std::size_t v = 0; v < V; ++v) {
        const GridTransition& t = g.transition[a * V + v];
        const std::size_t at = a * V + v;
        r[at] = t.reward;
        if (t.cell < 0) {
          std::fill(c + at * K, c + at * K + K, -1);
          std::fill(w + at * K, w + at * K + K, 0.0f);
          continue;
        }
        float weight[8];
        cornerWeights(g.dimension, {t.frac[0], t.frac[1], t.frac[2]}, weight);
        const std::uint32_t* corner = &g.corners[static_cast<std::size_t>(t.cell) << g.dimension];
        for (std::size_t k = 0; k < K; ++k) {
          c[at * K + k] = static_cast<std::int32_t>(corner[k]);
          w[at * K + k] = weight[k];
        }
      }
    });
  }
  p.discount = py::array_t<float>(A);
  std::copy(g.discount.begin(), g.discount.end(), p.discount.mutable_data());
  p.nextState = py::array_t<std::int32_t>(A);
  std::copy(g.actionTo.begin(), g.actionTo.end(), p.nextState.mutable_data());
  p.outIndptr = py::array_t<std::int32_t>(model.stateCount() + 1);
  std::copy(model.stateActionBegin.begin(), model.stateActionBegin.end(), p.outIndptr.mutable_data());
  // The model numbers each state's out-actions contiguously: indices are 0 .. A-1.
  p.outIndices = py::array_t<std::int32_t>(A);
  for (std::size_t a = 0; a < A; ++a) p.outIndices.mutable_data()[a] = static_cast<std::int32_t>(a);
  // Each vertex as the grid's coordinates (angle, distance, height, ... as its axes say;
  // a vertex at the avatar itself keeps its angle axis' value),
  // then on a grid with speed layers its layer's speed (with a learned opponent's layers,
  // its discrete state: graph state x phases + phase), and with turn layers the turn rate
  // (rad/s) last.
  const int D = grid.dimension(), layerColumn = D + (grid.layerAxis() ? 1 : 0);
  const int columns = layerColumn + (grid.turnAxis() ? 1 : 0);
  p.vertices = py::array_t<double>({V, static_cast<std::size_t>(columns)});
  for (std::size_t v = 0; v < V; ++v) {
    const TargetState e = grid.vertexState(v);
    const auto coordinates = grid.vertexCoordinates(v);
    double* row = p.vertices.mutable_data() + v * static_cast<std::size_t>(columns);
    for (int d = 0; d < D; ++d) row[d] = coordinates[static_cast<std::size_t>(d)];
    if (grid.layerAxis()) row[D] = grid.layerCoordinate(e);
    if (grid.turnAxis()) row[layerColumn] = e.turnRate;
  }
  p.tabulateSeconds = tabulated;
  p.arraysSeconds = since(started) - tabulated;
  return p;
}

py::array_t<float> PySession::train(const std::string& name, const py::object& learner, const py::object& sets,
                                    const py::object& progress, std::size_t snapshots, const py::object& onSnapshot) {
  const Behavior& b = behavior(name);
  // The scenario's learner block; another learner type starts from its defaults (as
  // --set behaviors.B.learner.type=OTHER resets the block).
  nlohmann::json config = b.config.value("learner", nlohmann::json::object());
  if (!learner.is_none() && config.value("type", std::string()) != learner.cast<std::string>())
    config = {{"type", learner.cast<std::string>()}};
  const std::vector<std::string> given = setsOf(sets);
  for (const std::string& set : given) {
    const std::size_t eq = set.find('=');
    if (eq == std::string::npos) throw Error(fmt::format("sets: expected 'key=value', found '{}'", set));
    config[set.substr(0, eq)] = nlohmann::json::parse(set.substr(eq + 1), nullptr, false).is_discarded()
                                    ? nlohmann::json(set.substr(eq + 1))
                                    : nlohmann::json::parse(set.substr(eq + 1));
  }
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    throw Error(fmt::format("progress: expected a callable taking a dict, or None, found an object of type {}",
                            typeName(progress)));
  if (!onSnapshot.is_none() && !PyCallable_Check(onSnapshot.ptr()))
    throw Error(fmt::format("on_snapshot: expected a callable taking a dict, or None, found an object of type {}",
                            typeName(onSnapshot)));
  if (snapshots > 1000) throw Error(fmt::format("snapshots: expected at most 1000, found {}", snapshots));
  TrainSettings settings;
  settings.behavior = name;
  settings.save = false;
  if (!learner.is_none() || !given.empty()) settings.learner = learnerFrom(config, name);
  // The one way every front end trains: its self-play rounds, memory plan and record.
  Trained trained = trainWatched(*session_, settings, progress, snapshots, onSnapshot);
  PolicyBehavior& table = trained.bundle.behaviors.at(name);
  if (trained.refined.count(name) != 0)
    throw Error(
        fmt::format("train: the learner {} refined its own grid ({} vertices); tables on refined grids are "
                    "not offered to Python yet",
                    table.record.value("learner", std::string()), table.table.vertexCount()));
  const nlohmann::json& report = trained.report["behaviors"][name];
  lastTrain_ = {{"behavior", name},
                {"learner", report["learner"]},
                {"updates", report["updates"]},
                {"seconds", report["seconds"]},
                {"final_residual", report["final_residual"]},
                {"curve", table.record["curve"]},
                {"stats", report["stats"]}};
  if (report.contains("rounds")) lastTrain_["rounds"] = report["rounds"];
  return tableArray(table.table);
}

py::dict PySession::compareTables(const std::string& name, const py::object& table, const py::object& reference) const {
  const Behavior& b = behavior(name);
  const QTable q = tableFrom(b, table), r = tableFrom(b, reference);
  const std::vector<double> positions = vertexPositions(*b.discretizer);
  Comparison c;
  {
    py::gil_scoped_release release;
    c = mgrl::compareTables(q, positions, r, positions, *b.discretizer);
  }
  py::dict d;
  d["value_rmse"] = c.rmse;
  d["greedy_agreement"] = c.agreement;
  d["reference_interpolated"] = c.interpolated;
  return d;
}

QTable PySession::tableFrom(const Behavior& b, const py::handle& value) const {
  const StateActionModel& model = session_->model();
  const std::size_t A = model.actionCount(), V = b.discretizer->vertexCount();
  const std::string where = fmt::format("tables['{}']", b.name);
  py::array a;
  if (py::isinstance<py::array>(value)) {
    a = py::reinterpret_borrow<py::array>(value);
  } else {
    // A nested list (or another array-like) converts as numpy.asarray would, to float32:
    // it has no dtype of its own to keep.
    try {
      a = py::module_::import("numpy").attr("asarray")(value, "float32");
    } catch (const py::error_already_set&) {
      throw Error(
          fmt::format("{}: expected a NumPy float32 array of shape ({}, {}), found an object of type {} "
                      "that NumPy does not convert to one",
                      where, A, V, typeName(value)));
    }
  }
  if (a.ndim() != 2 || static_cast<std::size_t>(a.shape(0)) != A || static_cast<std::size_t>(a.shape(1)) != V)
    throw Error(
        fmt::format("{}: expected shape ({}, {}) ({} actions of the graph x {} vertices of {}'s {} grid), "
                    "found shape {}",
                    where, A, V, A, V, b.name, b.discretizer->type(), shapeText(a)));
  if (!a.dtype().is(py::dtype::of<float>()))
    throw Error(fmt::format("{}: expected dtype float32, found {} (convert with table.astype(numpy.float32))", where,
                            py::str(a.dtype()).cast<std::string>()));
  const auto c = py::array_t<float, py::array::c_style>::ensure(a);  // a copy only if strided
  const float* d = c.data();
  for (std::size_t i = 0; i < A * V; ++i)
    if (!std::isfinite(d[i]))
      throw Error(fmt::format("{}: expected finite values, found {} at [{}, {}]", where, d[i], i / V, i % V));
  QTable q(model, V);
  q.setActionMajor({d, A * V});
  return q;
}

PolicyBundle PySession::readBundle(const std::filesystem::path& dir, std::string_view where) const {
  if (!std::filesystem::exists(dir / "manifest.json"))
    throw Error(fmt::format(
        "{}: expected a policy bundle's folder (with a manifest.json, as mgrl train or "
        "save_policy writes), found {}",
        where, std::filesystem::exists(dir) ? "a folder without one: " + dir.string() : "nothing at " + dir.string()));
  try {
    return loadPolicyBundle(dir, session_->model(), session_->graph.key);
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", where, e.what()));
  }
}

std::shared_ptr<PolicyBehavior> PySession::otherTable(const Behavior& b, bool trainMissing, std::string_view where) {
  if (const auto found = others_.find(b.name); found != others_.end()) return found->second;
  const Session& session = *session_;
  const std::filesystem::path dir =
      !policyDir_.empty() ? policyDir_
                          : defaultPolicyDirectory(
                                session.options.cacheDir.empty() ? defaultCacheDirectory() : session.options.cacheDir,
                                session.scenario, session.plugins(), session.graph.key);
  const std::string bundleName =
      policyDir_.empty() ? "the scenario's trained bundle" : fmt::format("the policy bundle {}", policyDir_.string());
  std::string why = policyDir_.empty() ? "no trained bundle" : "";
  if (!policyDir_.empty() || std::filesystem::exists(dir / "manifest.json")) {
    try {
      if (!bundle_) bundle_ = std::make_unique<PolicyBundle>(loadPolicyBundle(dir, session.model(), session.graph.key));
      const auto found = bundle_->behaviors.find(b.name);
      if (found == bundle_->behaviors.end()) {
        why = fmt::format("no table for it in {}", bundleName);
      } else if (found->second.key != b.key) {
        why = fmt::format("{}'s table was trained with other settings", bundleName);
      } else if (!found->second.grid.empty()) {
        why = fmt::format("{}'s table is on a refined grid", bundleName);
      } else {
        auto table = std::make_shared<PolicyBehavior>(found->second);
        others_[b.name] = table;
        return table;
      }
    } catch (const Error& e) {
      why = fmt::format("{} is unusable: {}", bundleName, e.what());
    }
  }
  if (!trainMissing)
    throw Error(fmt::format(
        "{}: expected a table for behaviour '{}' ({}), found none to play; pass one in tables "
        "(tables={{'{}': s.train('{}')}}), open the session with policy=FOLDER (a bundle mgrl train or save_policy "
        "wrote), or pass train_missing=True to train it here with {}",
        where, b.name, why, b.name, b.name, b.learner->type()));
  toStderr(
      fmt::format("mgrl: {} ({}): training {} with {} first (train_missing=True); "
                  "s.save_policy(FOLDER, tables) keeps tables for Session(..., policy=FOLDER)",
                  b.name, why, b.name, b.learner->type()));
  TrainSettings settings;
  settings.behavior = b.name;
  settings.save = false;
  Trained trained = trainWatched(session, settings, py::none());
  if (trained.refined.count(b.name) != 0)
    throw Error(fmt::format("{}: its learner {} refines its grid; train it with `mgrl train` first", b.name,
                            b.learner->type()));
  auto table = std::make_shared<PolicyBehavior>(std::move(trained.bundle.behaviors.at(b.name)));
  others_[b.name] = table;
  return table;
}

py::dict PySession::loadPolicy(const std::filesystem::path& dir) const {
  const PolicyBundle bundle = readBundle(dir, "load_policy");
  py::dict out;
  for (const auto& [name, table] : bundle.behaviors) {
    if (!table.grid.empty())
      throw Error(
          fmt::format("load_policy: {}'s table in {} is on a refined grid ({} vertices); tables on refined "
                      "grids are not offered to Python yet",
                      name, dir.string(), table.table.vertexCount()));
    out[py::str(name)] = tableArray(table.table);
  }
  return out;
}

PySession::Tables PySession::tablesFor(const py::object& tables, const std::string& learnerName, bool trainMissing,
                                       std::string_view where) {
  if (!py::isinstance<py::dict>(tables))
    throw Error(
        fmt::format("tables: expected a dict {{behaviour name: NumPy (A, V) float32 table}}, found an object "
                    "of type {}",
                    typeName(tables)));
  Tables out;
  for (const auto& [key, value] : tables.cast<py::dict>()) {
    const std::string name = py::str(key).cast<std::string>();
    const Behavior& b = behavior(name);
    out.behaviors[name] = std::make_shared<PolicyBehavior>(givenTable(b, tableFrom(b, value), learnerName, "python"));
  }
  for (const Behavior& b : session_->behaviors) {
    if (!out.behaviors.count(b.name)) out.behaviors[b.name] = otherTable(b, trainMissing, where);
    out.parts.push_back({b.discretizer.get(), &out.behaviors[b.name]->table, b.weight, b.activation, b.stance});
  }
  return out;
}

py::object PySession::evaluate(const py::object& tables, std::size_t trials, std::uint64_t seed,
                               const std::string& controller, double seconds, int horizon, bool trainMissing) {
  EvalSettings settings;
  settings.controller = {controller, horizon, 0};
  settings.trials = trials;
  settings.seconds = seconds;
  settings.seed = seed;
  settings.trialsField = "trials";
  settings.secondsField = "seconds";
  const ControllerRegistry& controllers = session_->plugins().controllers;
  checkEvalSettings(controllers, settings, {"controller", "horizon", "horizon_seconds"});
  Tables t;
  if (controllers.find(controller)->needsPolicy)
    t = tablesFor(tables.is_none() ? py::dict() : tables, "python", trainMissing, "evaluate");
  nlohmann::json report;
  {
    py::gil_scoped_release release;
    report = mgrl::evaluate(*session_, t.parts, settings);
  }
  return py::module_::import("json").attr("loads")(report.dump());
}

py::object PySession::simulate(const py::object& tables, long long avatars, double seconds, std::uint64_t seed,
                               const std::string& controller, int horizon, const py::object& bvhOut,
                               const py::object& gltfOut, const py::object& eventsOut, bool poses, bool trainMissing) {
  SimulateSettings settings;
  settings.controller = {controller, horizon, 0};
  settings.avatars = avatars;
  settings.seconds = seconds;
  settings.seed = seed;
  settings.poses = poses;
  auto path = [](const py::object& p) {
    return p.is_none() ? std::filesystem::path() : p.cast<std::filesystem::path>();
  };
  settings.bvhOut = path(bvhOut);
  settings.gltfOut = path(gltfOut);
  settings.eventsOut = path(eventsOut);
  settings.fields = SimulateFields::keywords();
  const ControllerRegistry& controllers = session_->plugins().controllers;
  checkSimulateSettings(controllers, settings);
  const bool needsPolicy = controllers.find(controller)->needsPolicy;
  Tables t;
  if (needsPolicy) t = tablesFor(tables.is_none() ? py::dict() : tables, "python", trainMissing, "simulate");
  Outputs outputs = prepareOutputs(settings.exportRequest(), session_->scenario);
  nlohmann::json report;
  {
    py::gil_scoped_release release;
    if (!captured_) captured_ = withCapture(*session_);
    report = mgrl::simulate(*captured_, settings, outputs, needsPolicy ? &t.parts : nullptr);
  }
  return py::module_::import("json").attr("loads")(report.dump());
}

std::unique_ptr<const Session> PySession::withCapture(const Session& session) {
  std::unique_ptr<const Session> captured = openSession(session.options, {.motion = true});
  if (captured->graph.key != session.graph.key)
    throw Error(fmt::format(
        "simulate: the capture of {} changed on disk since the session opened (graph {} now, "
        "{} then); open the session again",
        session.scenario.path.string(), captured->graph.key.substr(0, 12), session.graph.key.substr(0, 12)));
  return captured;
}

void PySession::savePolicy(const std::filesystem::path& path, const py::object& tables, const std::string& learnerName,
                           bool trainMissing) {
  Tables t = tablesFor(tables, learnerName, trainMissing, "save_policy");
  PolicyBundle bundle;
  bundle.graphKey = session_->graph.key;
  nlohmann::json given = nlohmann::json::object();
  for (const auto& [key, value] : tables.cast<py::dict>()) given[py::str(key).cast<std::string>()] = learnerName;
  bundle.provenance = trainingProvenance(*session_);
  bundle.provenance["tool"] = fmt::format("mgrl {} (Python)", kVersion);
  bundle.provenance["python_learners"] = given;
  for (const auto& [name, table] : t.behaviors) bundle.behaviors[name] = *table;
  py::gil_scoped_release release;
  savePolicyBundle(path, bundle);
}

py::array_t<float> PySession::tableArray(const QTable& q) const {
  const StateActionModel& model = session_->model();
  const std::size_t A = model.actionCount(), V = q.vertexCount();
  py::array_t<float> out({A, V});
  float* o = out.mutable_data();
  for (std::size_t s = 0; s < model.stateCount(); ++s) {
    const std::size_t first = model.stateActionBegin[s], n = q.actionsOf(s);
    for (std::size_t v = 0; v < V; ++v) {
      const float* row = q.row(s, v);
      for (std::size_t j = 0; j < n; ++j) o[(first + j) * V + v] = row[j];
    }
  }
  return out;
}

}  // namespace mgrl::python
