"""mgrl.compare: learners side by side on one behaviour, C++ ones by name and Python ones
as objects, with `mgrl compare`'s measures, learning curves and report.

    class MyLearner:
        name = "my_sarsa"
        def train(self, problem, budget, rng, observer):
            Q = np.zeros(problem.rewards.shape, np.float32)
            ...                                   # budget updates, drawing from rng
            observer.snapshot(Q, updates)         # at the points observer.snapshot_points
            return Q

    report = mgrl.compare(s, "hit", ["q_learning", "value_iteration", MyLearner()],
                          seeds=[1, 2], report="compare-out")

Every run is evaluated on the same trial starts (seed 1) as `mgrl compare` does, and
measured against value iteration on the behaviour's grid (value RMSE, greedy agreement);
snapshots taken along training are evaluated on the first `snapshot_trials` of those
starts, giving success-rate curves. The returned dict has mgrl compare's JSON layout, and
with `report=DIR` the same results.json, results.csv, curves.csv and index.html are
written there. A Python learner that raises stops the comparison with its traceback
(the exception propagates, nothing is written).
"""
import json
import time

import numpy as np

from . import _core


class Observer:
    """What a Python learner reports through: snapshots of its table along training (for
    the learning curve) and, optionally, progress.

    Parameters
    ----------
    budget : int
        The learner's number of updates.
    count : int
        How many snapshots compare wants, evenly spaced over the budget.

    Attributes
    ----------
    budget : int
        The learner's number of updates.
    snapshot_count : int
        How many snapshots compare wants.
    snapshot_points : list[int]
        The updates at which to take them: budget * i // count for i = 1..count.
    snapshots : list[dict[str, typing.Any]]
        Those taken: {"updates", "seconds", "residual", "table"}.
    """

    def __init__(self, budget, count):
        self.budget = int(budget)
        self.snapshot_count = int(count)
        # Evenly spaced, as the C++ learners take theirs: budget * i / n for i = 1..n.
        self.snapshot_points = [self.budget * i // count for i in range(1, count + 1)] if count else []
        self.snapshots = []
        self.spent = 0.0  # seconds in snapshot(): left out of the training time
        self.started = time.perf_counter()

    def snapshot(self, table, updates, residual=None):
        """Takes a copy of the table for the learning curve (the time it takes is left out
        of the training time).

        Parameters
        ----------
        table : numpy.typing.ArrayLike
            Q, shape (A, V).
        updates : int
            The updates made so far.
        residual : float | None
            The Bellman residual, if the learner measured one.

        Returns
        -------
        None
        """
        started = time.perf_counter()
        self.snapshots.append({"updates": int(updates), "seconds": started - self.started - self.spent,
                               "residual": residual, "table": np.array(table, dtype=np.float32, copy=True)})
        self.spent += time.perf_counter() - started

    def progress(self, updates, total=None):
        """Where training is; compare does not show it.

        Parameters
        ----------
        updates : int
            The updates made so far.
        total : int | None
            Of how many.

        Returns
        -------
        None
        """


def _name(learner):
    if isinstance(learner, str):
        return learner
    return str(getattr(learner, "name", type(learner).__name__))


def _plain(x):
    """NumPy scalars (a Python learner's observer may report them) as plain numbers for JSON."""
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"compare: expected numbers, lists and dicts in a run, found {type(x).__name__}")


def compare(session, behavior, learners, seeds=(1,), trials=100, seconds=10.0, snapshots=10, snapshot_trials=None,
            budget=1_000_000, report=None, log=print):
    """Learners side by side on one behaviour, as mgrl compare runs them: C++ learners by
    name and Python learner objects, each with every seed (a C++ learner without a seed
    parameter runs once), measured against value iteration and evaluated on the same trial
    starts.

    Parameters
    ----------
    session : Session
        The scenario.
    behavior : str
        One of its behaviours.
    learners : collections.abc.Sequence[typing.Any]
        Registered C++ learner names and objects with train(problem, budget, rng,
        observer) returning a float32 (A, V) table.
    seeds : collections.abc.Iterable[int]
        The seeds each learner runs with.
    trials : int
        Trials per run, on the same starts (seed 1).
    seconds : float
        Each trial's length.
    snapshots : int
        Snapshots per run for the learning curves.
    snapshot_trials : int | None
        Trials per snapshot (the first of the starts); None: min(50, trials).
    budget : int
        The Python learners' number of updates.
    report : str | os.PathLike[str] | None
        A folder to write results.json, results.csv, curves.csv and index.html to.
    log : collections.abc.Callable[..., object] | None
        Where progress lines go (print); None: nowhere.

    Returns
    -------
    dict[str, typing.Any]
        mgrl compare's report: "runs", "learners" (mean and sd of each measure),
        "reference", ...

    Raises
    ------
    mgrl.Error
        Unknown learners, no seeds, or a report folder that cannot be written; an
        exception a Python learner raises propagates.
    """
    if isinstance(learners, (str, bytes)) or not learners:
        raise _core.Error("learners: expected a list of C++ learner names and Python learner objects, found "
                          f"{learners!r}")
    names = [_name(x) for x in learners]
    if len(set(names)) != len(names):
        raise _core.Error(f"learners: expected each learner once, found {names}")
    for x in learners:
        if not isinstance(x, str) and not callable(getattr(x, "train", None)):
            raise _core.Error(f"learners: expected a name or an object with train(problem, budget, rng, observer), "
                              f"found {x!r}")
    for x in learners:
        if isinstance(x, str):
            _core.learner_parameters(x)  # an unknown name is refused before anything trains
    seeds = [int(s) for s in seeds]
    if not seeds:
        raise _core.Error("seeds: expected at least one seed")
    snapshot_trials = min(50, trials) if snapshot_trials is None else int(snapshot_trials)
    say = log or (lambda *_: None)
    if report is not None:  # refused now, not after the training
        import os
        import tempfile
        try:
            os.makedirs(report, exist_ok=True)
            tempfile.TemporaryFile(dir=report).close()
        except OSError as e:
            raise _core.Error(f"report {report}: expected a folder where files can be written, found {e.strerror}")

    say(f"compare: reference: value_iteration on {behavior}'s grid")
    # When value_iteration is also a run, its one training (with snapshots) serves both.
    reference_taken = []
    reference = session.train(behavior, learner="value_iteration", snapshots=snapshots if "value_iteration" in names
                              else 0, on_snapshot=reference_taken.append)
    reference_done = session.last_train
    reference_seconds = reference_done.get("seconds")
    problem = None
    runs = []

    def evaluate(table, count):
        # The other behaviours' tables: the session's bundle, else trained once (said on stderr).
        return session.evaluate({behavior: table}, trials=count, seed=1, seconds=seconds, train_missing=True)

    def curve_of(points):
        out = []
        for p in points:
            e = evaluate(p["table"], snapshot_trials)
            out.append([p["updates"], p["seconds"], p.get("residual"), e["success_rate"],
                        e["mean_time_to_hit_s"], e["mean_return"]])
        return out

    for learner, name in zip(learners, names):
        cpp = isinstance(learner, str)
        # A C++ learner without a seed parameter is deterministic: one run stands for all.
        seeded = not cpp or "seed" in _core.learner_parameters(learner)
        for seed in (seeds if seeded else seeds[:1]):
            label = f"{name} seed {seed}" if seeded else name
            say(f"compare: [{len(runs) + 1}] {label}")
            taken = []
            if cpp and learner == "value_iteration":
                table, taken, done = reference, reference_taken, reference_done
            if cpp:
                if learner != "value_iteration":
                    sets = {"seed": seed} if seeded else {}
                    table = session.train(behavior, learner=learner, sets=sets, snapshots=snapshots,
                                          on_snapshot=taken.append)
                    done = session.last_train
                train_seconds, updates = done["seconds"], done["updates"]
                residual, curve = done["final_residual"], done["curve"]
                coverage = done.get("stats", {}).get("cell_coverage")
            else:
                if problem is None:
                    problem = session.problem(behavior)
                observer = Observer(budget, snapshots)
                table = learner.train(problem, budget, np.random.default_rng(seed), observer)
                train_seconds = time.perf_counter() - observer.started - observer.spent
                taken = observer.snapshots
                updates, residual, curve, coverage = budget, None, [], None
            evaluated = evaluate(table, trials)
            measured = session.compare_tables(behavior, table, reference)
            run = {
                "learner": name,
                "seed": seed if seeded else None,
                "policy": None,
                "success_rate": evaluated["success_rate"],
                "mean_time_to_hit_s": evaluated["mean_time_to_hit_s"],
                "mean_return": evaluated["mean_return"],
                "train_seconds": train_seconds,
                "updates": updates,
                "table_bytes": int(np.asarray(table).nbytes),
                "final_residual": residual,
                "decision_us": 1e6 / evaluated["decisions_per_second"] if evaluated["decisions_per_second"] else None,
                "value_rmse": measured["value_rmse"],
                "greedy_agreement": measured["greedy_agreement"],
                "reference_interpolated": measured["reference_interpolated"],
                "nonzero_share": float(np.count_nonzero(table)) / np.asarray(table).size,
                "cell_coverage": coverage,
                "curve": curve,
                "snapshots": {"columns": _core.snapshot_columns(), "points": curve_of(taken)} if taken else None,
                "python": not cpp,
            }
            if taken:
                rates = " ".join(f"{100 * p[3]:.0f}" for p in run["snapshots"]["points"])
                say(f"compare: {label}: success % along training ({len(taken)} snapshots of {snapshot_trials} "
                    f"trials): {rates}")
            runs.append(run)

    result = {
        "scenario": str(session.scenario),
        "scenario_name": str(session.scenario).rsplit("/", 1)[-1].rsplit(".", 1)[0],
        "behavior": behavior,
        "learner_names": names,
        "seeds": seeds,
        "trials": trials,
        "seconds_per_trial": seconds,
        "reference": {"learner": "value_iteration", "policy": None, "grid": None, "vertices": reference.shape[1],
                      "sets": [], "train_seconds": reference_seconds,
                      "description": f"value iteration on the behaviour's grid ({reference.shape[1]} vertices)"},
        "snapshots": snapshots,
        "snapshot_trials": snapshot_trials if snapshots else None,
        "runs": runs,
        "learners": {},
        "flags": [],
    }
    # The same summaries as mgrl compare's (one C++ function): mean and sd per metric, null
    # where a run lacks it, and the success curve over seeds.
    result["learners"] = json.loads(_core.learner_summaries(json.dumps(runs, default=_plain), names))
    for name in names:
        mine = [r for r in runs if r["learner"] == name]
        for r in mine:
            if r["greedy_agreement"] < 0.9:  # as mgrl compare flags
                result["flags"].append(
                    f"{name}{' seed ' + str(r['seed']) if r['seed'] is not None else ''}: its greedy policy agrees "
                    f"with the reference's on {100 * r['greedy_agreement']:.1f} % of (state, vertex) pairs")
    if report is not None:
        _core.write_compare_report(str(report), json.dumps(result, default=_plain))
        result["report"] = str(report) + "/index.html"
    say(text(result).rstrip())
    return result


def _count(x):
    """1.23 M, 456.0 k: as mgrl prints counts."""
    for scale, unit in ((1e9, " G"), (1e6, " M"), (1e3, " k")):
        if abs(x) >= scale:
            return f"{x / scale:.2f}{unit}" if unit != " k" else f"{x / scale:.1f}{unit}"
    return f"{x:.0f} "


def text(result):
    """The table mgrl compare prints, for a report from compare().

    Parameters
    ----------
    result : dict[str, typing.Any]
        compare()'s report.

    Returns
    -------
    str
    """
    lines = [f"compare {result['behavior']} on {result['scenario_name']}: {len(result['runs'])} "
             f"run{'s' if len(result['runs']) != 1 else ''}, {result['trials']} trials each on the same starts; "
             f"reference: {result['reference']['description']}",
             f"{'learner (mean ± sd)':<24} {'success %':>14} {'time to hit s':>13} {'train s':>13} {'updates':>12} "
             f"{'decide us':>10} {'V RMSE':>11} {'agreement %':>11} {'non-zero %':>10}"]

    def cell(learner, key, scale, form):
        mean, sd = learner["mean"][key], learner["sd"][key]
        if mean is None:
            return "n/a"
        return form.format(scale * mean, scale * sd)

    for name, l in result["learners"].items():
        lines.append(f"{name:<24} {cell(l, 'success_rate', 100, '{:.1f} ± {:.1f}'):>14} "
                     f"{cell(l, 'mean_time_to_hit_s', 1, '{:.2f} ± {:.2f}'):>13} "
                     f"{cell(l, 'train_seconds', 1, '{:.2f} ± {:.2f}'):>13} {cell(l, 'updates', 1e-6, '{:.1f}M'):>12} "
                     f"{cell(l, 'decision_us', 1, '{:.2f}'):>10} {cell(l, 'value_rmse', 1, '{:.3g}'):>11} "
                     f"{cell(l, 'greedy_agreement', 100, '{:.1f}'):>11} {cell(l, 'nonzero_share', 100, '{:.1f}'):>10}")
    curves = [(name, l["success_curve"]) for name, l in result["learners"].items() if l["success_curve"]]
    if curves:
        lines.append(f"success % along training (mean over seeds; {result['snapshot_trials']} trials per snapshot), "
                     "at updates:")
        for name, curve in curves:
            lines.append(f"{name:<24}" + "".join(f" {100 * p[2]:.0f}@{_count(p[0]).strip()}" for p in curve))
    lines += [f"flag: {flag}" for flag in result["flags"]]
    if "report" in result:
        lines.append(f"report: {result['report']}")
    return "\n".join(lines) + "\n"
