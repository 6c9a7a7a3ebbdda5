"""mgrl from Python: the motion-graph learning problem as NumPy arrays, and mgrl's C++
learners on it.

    import mgrl
    s = mgrl.Session("boxing")                          # a scenario the module carries, or a YAML path;
                                                        # data, cache, sets as on the command line;
                                                        # policy=FOLDER: a saved bundle's tables
    p = s.problem("approach")                           # the tabulated problem
    q = s.train("approach", learner="value_iteration")  # (A, V) float32
    r = s.evaluate({"approach": q}, trials=300)         # mgrl eval --json's figures
    s.save_policy("bundle", {"approach": q}, learner="my_vi")  # for mgrl eval --policy

`p` holds exactly what the C++ learners back up:

    p.rewards    float32 (A, V)     r(v, a)
    p.corners    int32   (A, V, K)  vertices of the cell where vertex v lands after
                                    action a; -1 where it leaves the grid
    p.weights    float32 (A, V, K)  their interpolation weights (0 with corner -1)
    p.discount   float32 (A,)       gamma ** (frames of a)
    p.next_state int32   (A,)       the graph state action a ends in
    p.out_actions (indptr int32 (S+1,), indices int32 (A,)): the actions leaving each state
    p.vertices   float64 (V, D)     each vertex's grid coordinates (on a grid with speed
                                    layers, the layer's speed as a further column; with a
                                    turning target's turn layers, its turn rate, rad/s, last)

One value-iteration backup is

    Q[a, v] = R[a, v] + discount[a] * sum_k W[a, v, k] * max over a' in out(next_state[a])
              of Q[a', C[a, v, k]]                        (terms with C = -1 count 0)

which is the paper's sec. 4.2 backup with the grid's multilinear interpolation (the max
is taken of the interpolated row, as the C++ code does: max_a' sum_k, not sum_k max).
On a grid with speed layers (moving targets) a vertex lands exactly on its layer, so the
corners are one layer's and the formula is the same (likewise a turning target's turn
layers); grids whose vertices are partly
interpolated (a refined kd-tree's hanging vertices) are refused for now.

Session:
    graph            dict of read-only NumPy views of the graph (no copy): state_frame,
                     state_action_begin, action_from, action_to, action_frame_begin,
                     action_frames, action_displacement (A, 3: dx, dz, dyaw), frame_root,
                     hits and kicks (structured: action, offset, hand, x, y, z, weight)
                     with action_hit_begin / action_kick_begin, frame_time
    problem(b)       the tabulated problem above
    train(b, learner=None, sets=None, progress=None)
                     any registered C++ learner (the scenario's by default; sets are its
                     parameters); progress(dict) about ten times a second; Ctrl-C raises
                     KeyboardInterrupt
    evaluate(tables=None, trials=300, seed=1, controller="policy", seconds=10, horizon=3,
             train_missing=False)
                     mgrl eval's trials: tables {behaviour: float32 (A, V)}; the other
                     behaviours from the session's policy bundle (Session(..., policy=)),
                     else the scenario's trained bundle; a behaviour in neither is an
                     error saying how to get its table, or with train_missing=True is
                     trained first (said on stderr)
    simulate(tables=None, avatars=2, seconds=10, seed=1, controller="policy", horizon=3,
             bvh_out=None, gltf_out=None, events_out=None, poses=False, train_missing=False)
                     mgrl simulate --json's report as a dict: the world run headless on
                     the tables (as evaluate's), hits by part and side; BVH, glTF and
                     hit events written as the command line writes them
    save_policy(path, tables, learner="python", train_missing=False)
                     a complete policy bundle mgrl eval/simulate/serve/compare accept
                     (the other behaviours' tables as evaluate finds them)
    load_policy(path) a policy bundle's tables, {behaviour: float32 (A, V)}

load_policy(path, session)
                     a policy bundle's tables for session's graph, as Session.load_policy
scenarios()          the names of the scenarios shipped with the module
scenario_path(name) the path of one of them (boxing.yaml, ...), from any folder
__version__          the version, as `mgrl --version` prints it

inspect(files)       mgrl inspect --json's report on motion files (BVH, ASF/AMC) as a
                     dict: joints, roles, frames, height, contacts, effective punches
                     and kicks; the loader's warnings as Python warnings
bout_stats(bouts=(), snu=False, against=(), data=None)
                     mgrl stats --json's report (docs/stats.md) as a dict: bouts are
                     folders of BVH files (one per fighter) or quoted patterns, looked
                     up in the working folder, then in data; snu adds the SNU sparring
                     capture; against (bouts) compares the two groups
"""
import json as _json
import os as _os
import pathlib as _pathlib
import sys as _sys
import warnings as _warnings

try:  # the C++ core hands out NumPy arrays: without NumPy it cannot start
    import numpy as _numpy  # noqa: F401
except ImportError as _error:
    raise ImportError(f"mgrl: expected NumPy importable by this Python ({_sys.executable}), found none ({_error}); "
                      "install it for this Python, or use Debian's /usr/bin/python3 with python3-numpy") from None
try:
    from . import _core
except ImportError as _error:
    _built = sorted(p.name for p in _pathlib.Path(__file__).resolve().parent.glob("_core*"))
    raise ImportError(f"mgrl: expected the C++ core built for this Python ({_sys.executable}, "
                      f"{_sys.implementation.cache_tag}), found {', '.join(_built) or 'none'} ({_error}); build or "
                      "install mgrl with this Python, or use the one it was built for (Debian's /usr/bin/python3)"
                      ) from None
from ._core import Error, Problem, Session, __version__  # noqa: F401
from .compare import Observer, compare  # noqa: F401
from .env import MotionGraphEnv, MotionGraphVectorEnv  # noqa: F401

__all__ = ["Error", "Problem", "Session", "MotionGraphEnv", "MotionGraphVectorEnv", "Observer", "compare",
           "bout_stats", "load_policy", "scenarios", "scenario_path"]  # mgrl.inspect too, left out here not to hide the standard library's inspect


def inspect(files):
    """What is in motion files, as mgrl inspect --json reports it with its defaults; the
    loader's warnings as Python warnings.

    Parameters
    ----------
    files : str | os.PathLike[str] | collections.abc.Sequence[str | os.PathLike[str]]
        One BVH or ASF/AMC file, or several; every file is read before any is reported.

    Returns
    -------
    dict[str, typing.Any]
        {"files": [{"path", "joints", "joint_names", "roles", "frames", "fps", "height_m",
        "punches", "kicks", ...}]}.

    Raises
    ------
    mgrl.Error
        A file that cannot be read, naming it, the line and what was expected.
    """
    if isinstance(files, (str, bytes)) or hasattr(files, "__fspath__"):
        files = [files]
    result = _json.loads(_core._inspect([_os.fsdecode(f) for f in files]))
    for line in result["warnings"]:
        _warnings.warn(line, stacklevel=2)
    return result["report"]


def bout_stats(bouts=(), snu=False, against=(), data=None):
    """Distance, facing, strikes, foot skate and more of bouts, real or synthesized, as
    mgrl stats --json reports them (docs/stats.md).

    Parameters
    ----------
    bouts : collections.abc.Sequence[str | os.PathLike[str]]
        Folders of BVH files (one per fighter) or quoted patterns, looked up in the working
        folder, then in data.
    snu : bool
        Add the SNU sparring capture.
    against : collections.abc.Sequence[str | os.PathLike[str]]
        Bouts to compare the first group with.
    data : str | os.PathLike[str] | None
        The motion-capture folder; None as Session's.

    Returns
    -------
    dict[str, typing.Any]
        {"params", "bouts", "pooled"}, or with against {"params", "real", "synthetic",
        "wasserstein1"}.

    Raises
    ------
    mgrl.Error
        A bout that cannot be read, naming it.
    """
    if isinstance(bouts, (str, bytes)) or isinstance(against, (str, bytes)):
        raise TypeError("bout_stats: expected bouts and against as lists of folders or patterns, found a string")
    bouts = [_os.fsdecode(b) for b in bouts]
    against = [_os.fsdecode(b) for b in against]
    result = _json.loads(_core._bout_stats(bouts, bool(snu), against, None if data is None else _os.fsdecode(data)))
    for line in result["warnings"]:
        _warnings.warn(line, stacklevel=2)
    return result["report"]


def load_policy(path, session):
    """A policy bundle's tables, ready for session.evaluate(tables).

    Parameters
    ----------
    path : str | os.PathLike[str]
        The bundle's folder (mgrl train's or Session.save_policy's).
    session : Session
        A session on the graph the bundle was made on.

    Returns
    -------
    dict[str, numpy.typing.NDArray[numpy.float32]]
        {behaviour: Q of shape (A, V)}.

    Raises
    ------
    mgrl.Error
        The folder holds no bundle, or one made on another graph.
    """
    return session.load_policy(_os.fspath(path))


def _scenario_folder():
    return _pathlib.Path(__file__).resolve().parent / "scenarios"


def scenarios():
    """The scenarios shipped with the module: each opens from any folder as
    mgrl.Session(name).

    Returns
    -------
    list[str]
        Their file names ("boxing.yaml", ...), sorted.
    """
    return sorted(p.name for p in _scenario_folder().glob("*.yaml"))


def scenario_path(name):
    """The path of a scenario shipped with the module, from any folder:
    mgrl.Session(mgrl.scenario_path("boxing.yaml")).

    Parameters
    ----------
    name : str | os.PathLike[str]
        A scenario's file name ("boxing.yaml", "spar_learned.yaml", ...; ".yaml" may be
        left out).

    Returns
    -------
    str

    Raises
    ------
    FileNotFoundError
        No such scenario, naming those there.
    ValueError
        A path, not a file name.
    """
    folder = _scenario_folder()
    name = _os.fsdecode(name)
    if _os.sep in name or (_os.altsep and _os.altsep in name):
        raise ValueError(f"scenario_path: expected a scenario's file name (e.g. 'boxing.yaml'), found a path {name!r}")
    path = folder / (name if name.endswith(".yaml") else name + ".yaml")
    if not path.is_file():
        raise FileNotFoundError(f"scenario_path: expected one of {', '.join(scenarios()) or 'none'} in {folder}, "
                                f"found no {path.name}")
    return str(path)
