#pragma once
// The docstrings of mgrl.Session and mgrl.Problem, in the NumPy docstring convention: what
// help() shows, and what scripts/python_stubs.py reads the stubs' types from (each
// parameter's and return's type is a Python type expression). Kept here so that the
// bindings (session.cpp) read as a list of members.
namespace mgrl::python::doc {

inline constexpr const char* kSession =
    R"(A scenario opened for Python: its motion graph, tabulated problems, C++ learners, eval's
trials, the world run headless and policy bundles.

Parameters
----------
scenario : str | os.PathLike[str]
    A scenario's YAML file, or the name of one the module carries ("boxing",
    mgrl.scenarios()) when no such file is in the current folder.
data : str | os.PathLike[str] | None
    The motion-capture folder; None: MGRL_DATA, the user data folder, then the
    checkout's ../shared/mocap.
cache : str | os.PathLike[str] | None
    The cache folder for graphs and trained bundles; None: ~/.cache/mgrl.
sets : dict[str, object] | list[str] | None
    Scenario overrides, as the command line's --set: {"behaviors.hit.reward.sigma": 0.2}
    or ["key=value", ...].
policy : str | os.PathLike[str] | None
    A policy bundle's folder (mgrl train's or save_policy's) whose tables evaluate and
    simulate play for the behaviours they are not given.

Raises
------
mgrl.Error
    A scenario, override, capture or bundle that cannot be used, saying where and why.)";

inline constexpr const char* kBehaviors = R"(The scenario's behaviours, in its order.

Returns
-------
list[str]
    Their names ("approach", "hit", ...).)";

inline constexpr const char* kScenario = R"(The scenario's file.

Returns
-------
os.PathLike[str]
    Its path, as opened.)";

inline constexpr const char* kGraph = R"(The motion graph as read-only NumPy views of the session's memory (no copy).

Returns
-------
dict[str, typing.Any]
    "state_frame", "state_action_begin" (S + 1), "action_from", "action_to",
    "action_frame_begin", "action_frames", "action_displacement" (A, 3: dx, dz, dyaw),
    "frame_root" (frames, 3), "hits" and "kicks" (structured: action, offset, hand, x, y,
    z, weight) with "action_hit_begin" and "action_kick_begin", "joint_names",
    "joint_positions" (frames, joints, 3), "frame_time" (s), "states", "actions".)";

inline constexpr const char* kProblem =
    R"(A behaviour's tabulated problem: what the C++ learners back up, as NumPy arrays.

Parameters
----------
behavior : str
    One of the scenario's behaviours.

Returns
-------
Problem
    Rewards, landing corners and weights, discounts and next states (mgrl's docstring
    gives the backup).

Raises
------
mgrl.Error
    An unknown behaviour, or a grid with interpolated (hanging) vertices.)";

inline constexpr const char* kTrain =
    R"(Trains a behaviour with a registered C++ learner, as mgrl train does (its self-play
rounds and memory plan), without saving.

Parameters
----------
behavior : str
    One of the scenario's behaviours.
learner : str | None
    A registered learner ("q_learning", "value_iteration", ...); None: the scenario's.
sets : dict[str, object] | list[str] | None
    The learner's parameters: {"budget": 2000000} or ["budget=2000000"].
progress : collections.abc.Callable[[dict[str, typing.Any]], object] | None
    Called about ten times a second with {"behavior", "updates", "total", "seconds",
    "residual"} (residual None until one is measured); an exception it raises stops
    training and propagates.
snapshots : int
    How many tables to take along training, evenly spaced (at most 1000).
on_snapshot : collections.abc.Callable[[dict[str, typing.Any]], object] | None
    Called with {"updates", "seconds", "residual", "table"} for each snapshot.

Returns
-------
numpy.typing.NDArray[numpy.float32]
    Q, shape (A, V): actions of the graph x vertices of the behaviour's grid. last_train
    holds the run's figures.

Raises
------
mgrl.Error
    Bad arguments, or a learner that refines its grid.
KeyboardInterrupt
    Ctrl-C during training.)";

inline constexpr const char* kLastTrain = R"(What the last train() reported.

Returns
-------
dict[str, typing.Any] | None
    {"behavior", "learner", "updates", "seconds", "final_residual", "curve", "stats"}
    and "rounds" for self-play; the curve's points are {"updates", "seconds", "residual",
    "mean_residual"}. None before any train().)";

inline constexpr const char* kCompareTables =
    R"(How a table compares with a reference on the same behaviour's grid, as mgrl compare
measures it.

Parameters
----------
behavior : str
    One of the scenario's behaviours.
table : numpy.typing.NDArray[numpy.float32]
    Q, shape (A, V).
reference : numpy.typing.NDArray[numpy.float32]
    The reference Q (value iteration's, say), shape (A, V).

Returns
-------
dict[str, float]
    Over every (state, vertex) pair, with V(s, v) the max of Q over s's out-actions:
    "value_rmse" (root mean square of V - V_reference), "greedy_agreement" (the share of
    pairs where the table's greedy action is the reference's best, within 1e-6) and
    "reference_interpolated" (False here: the same grid).)";

inline constexpr const char* kEvaluate = R"(mgrl eval's trials on tables from Python.

Parameters
----------
tables : dict[str, numpy.typing.NDArray[numpy.float32]] | None
    {behaviour: Q of shape (A, V)}; the behaviours left out come from the session's
    policy bundle, else the scenario's trained bundle.
trials : int
    Trials, each from its own random start.
seed : int
    The starts' seed: the same seed gives the same starts.
controller : str
    "policy" (the tables), "online_search", "random", or another registered controller.
seconds : float
    Each trial's length.
horizon : int
    online_search's lookahead, in actions.
train_missing : bool
    Train a behaviour that is in no bundle first (said on stderr) instead of refusing.

Returns
-------
dict[str, typing.Any]
    mgrl eval --json's report: "success_rate", "successes", "mean_return",
    "mean_time_to_hit_s", "decisions", "random_baseline", ...

Raises
------
mgrl.Error
    A table of the wrong shape or dtype or with a non-finite value, an unknown
    behaviour or controller, or a missing table without train_missing.)";

inline constexpr const char* kSimulate =
    R"(The world run headless on tables from Python, as mgrl simulate --json reports it.

Parameters
----------
tables : dict[str, numpy.typing.NDArray[numpy.float32]] | None
    As evaluate's.
avatars : int
    How many avatars (pairs spar).
seconds : float
    Seconds of motion.
seed : int
    The run's seed.
controller : str
    As evaluate's.
horizon : int
    As evaluate's.
bvh_out : str | os.PathLike[str] | None
    A folder to write each avatar's BVH to.
gltf_out : str | os.PathLike[str] | None
    A .glb file to write the run to.
events_out : str | os.PathLike[str] | None
    A file to write the hit events to (JSON lines).
poses : bool
    Whether the report holds every frame's pose.
train_missing : bool
    As evaluate's.

Returns
-------
dict[str, typing.Any]
    "avatars", "frames", "hits", "blocked", "decisions", "hits_by_part",
    "hits_by_avatar", "bodies", ...

Raises
------
mgrl.Error
    As evaluate's, or an output that cannot be written.)";

inline constexpr const char* kSavePolicy =
    R"(Writes a complete policy bundle that mgrl eval, simulate, serve and compare accept.

Parameters
----------
path : str | os.PathLike[str]
    The bundle's folder (replaced if it holds one).
tables : dict[str, numpy.typing.NDArray[numpy.float32]]
    {behaviour: Q of shape (A, V)}; the others as evaluate finds them.
learner : str
    The learner's name the bundle records for the tables given.
train_missing : bool
    As evaluate's.

Returns
-------
None

Raises
------
mgrl.Error
    As evaluate's; nothing is written then.)";

inline constexpr const char* kLoadPolicy = R"(A policy bundle's tables for this session's graph.

Parameters
----------
path : str | os.PathLike[str]
    The bundle's folder (mgrl train's or save_policy's).

Returns
-------
dict[str, numpy.typing.NDArray[numpy.float32]]
    {behaviour: Q of shape (A, V)}.

Raises
------
mgrl.Error
    No bundle there, one made on another graph, or a table on a refined grid.)";

inline constexpr const char* kProblemClass =
    R"(A behaviour's tabulated problem (Session.problem): the arrays the C++ learners back up.
One backup is Q[a, v] = rewards[a, v] + discount[a] * sum_k weights[a, v, k] *
max over a' in out(next_state[a]) of Q[a', corners[a, v, k]], terms with corner -1
counting 0.)";

inline constexpr const char* kBehavior = R"(The behaviour's name.

Returns
-------
str)";
inline constexpr const char* kRewards = R"(r(v, a): the reward of action a from vertex v.

Returns
-------
numpy.typing.NDArray[numpy.float32]
    Shape (A, V).)";
inline constexpr const char* kCorners =
    R"(The vertices of the cell where vertex v lands after action a; -1 where it leaves the grid.

Returns
-------
numpy.typing.NDArray[numpy.int32]
    Shape (A, V, K), K = 2 ** dimension.)";
inline constexpr const char* kWeights = R"(The corners' interpolation weights (0 with corner -1).

Returns
-------
numpy.typing.NDArray[numpy.float32]
    Shape (A, V, K).)";
inline constexpr const char* kDiscount = R"(gamma ** (frames of action a).

Returns
-------
numpy.typing.NDArray[numpy.float32]
    Shape (A,).)";
inline constexpr const char* kNextState = R"(The graph state each action ends in.

Returns
-------
numpy.typing.NDArray[numpy.int32]
    Shape (A,).)";
inline constexpr const char* kVertices =
    R"(Each vertex's grid coordinates (angle, distance, height, ... as the grid's axes say);
with speed layers the layer's speed as a further column, with turn layers the turn rate
(rad/s) last.

Returns
-------
numpy.typing.NDArray[numpy.float64]
    Shape (V, columns).)";
inline constexpr const char* kStates = R"(The graph's state count, S.

Returns
-------
int)";
inline constexpr const char* kActions = R"(The graph's action count, A.

Returns
-------
int)";
inline constexpr const char* kDimension = R"(The grid's dimension, D (K = 2 ** D corners a cell).

Returns
-------
int)";
inline constexpr const char* kVertexCount = R"(The grid's vertex count, V.

Returns
-------
int)";
inline constexpr const char* kTabulateSeconds = R"(Seconds the C++ tabulation took.

Returns
-------
float)";
inline constexpr const char* kArraysSeconds = R"(Seconds filling the NumPy arrays took.

Returns
-------
float)";
inline constexpr const char* kOutActions =
    R"(The actions leaving each state, as a CSR pair: state s's are indices[indptr[s]:indptr[s + 1]].

Returns
-------
tuple[numpy.typing.NDArray[numpy.int32], numpy.typing.NDArray[numpy.int32]]
    (indptr, shape (S + 1,); indices, shape (A,)).)";

}  // namespace mgrl::python::doc
