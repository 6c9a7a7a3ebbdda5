"""What the Python module costs (DESIGN.md's budget is measured here, not in
tests): building the problem's arrays against the C++ tabulation, a value-iteration sweep
in NumPy against the C++ one, the environment's single step and the vectorised one, and
that viewing the graph's arrays copies nothing. Medians of --runs runs.

    PYTHONPATH=build/python python3 bench/python_bench.py [--runs N] [--quick] [--scenario S]
"""
import argparse
import os
import pathlib
import resource
import statistics
import sys
import time

import numpy as np

import mgrl

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "python"))
from test_problem import numpy_value_iteration  # noqa: E402  (the tests' twenty lines)


def rss_mb():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize() / 1e6


def median_of(runs, measure):
    return statistics.median(measure() for _ in range(runs))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="fewer steps, one run")
    parser.add_argument("--scenario", default=str(ROOT / "scenarios" / "boxing.yaml"))
    parser.add_argument("--behavior", default="hit")
    args = parser.parse_args()
    runs = 1 if args.quick else args.runs
    s = mgrl.Session(args.scenario)
    b = args.behavior

    # 1. The problem's arrays against the C++ tabulation (the arrays may take at most twice it).
    problems = [s.problem(b) for _ in range(runs)]
    tabulate = statistics.median(p.tabulate_seconds for p in problems)
    arrays = statistics.median(p.arrays_seconds for p in problems)
    p = problems[-1]
    A, V, K = p.corners.shape
    print(f"problem {b}: {A} actions x {V} vertices x {K} corners; C++ tabulation {tabulate:.3f} s, "
          f"filling the NumPy arrays {arrays:.3f} s more ({(tabulate + arrays) / tabulate:.2f}x the tabulation; "
          f"budget 2x)")
    del problems

    # 2. One value-iteration sweep: NumPy (the tests' formula) against the C++ learner's.
    numpy_sweep = median_of(runs, lambda: timed(lambda: numpy_value_iteration(p, sweeps=1)))
    s.train(b, learner="value_iteration")
    done = s.last_train
    cpp_sweep = done["seconds"] * A * V / done["updates"]
    print(f"value-iteration sweep: NumPy {numpy_sweep:.3f} s, C++ {cpp_sweep:.4f} s "
          f"({numpy_sweep / cpp_sweep:.0f}x; the C++ sweep on {os.cpu_count()} threads)")

    # 3. The environment: one step from Python, and 1,024 stepped in one call.
    env = mgrl.MotionGraphEnv(s, b)
    steps = 20_000 if args.quick else 200_000

    def single():
        env.reset(seed=1)
        started = time.perf_counter()
        for _ in range(steps):
            _, _, terminated, truncated, _ = env.step(0)
            if terminated or truncated:
                env.reset()
        return (time.perf_counter() - started) / steps

    print(f"MotionGraphEnv.step: {1e6 * median_of(runs, single):.2f} us a step (budget 5 us)")
    for n in (1024,):
        vec = mgrl.MotionGraphVectorEnv(s, b, n)
        rounds = 50 if args.quick else 400
        rng = np.random.default_rng(1)

        def vector():
            obs, info = vec.reset(seed=1)
            counts = info["action_mask"].sum(axis=1)
            started = time.perf_counter()
            for _ in range(rounds):
                actions = (rng.random(n) * counts).astype(np.int64)  # a legal action each
                obs, reward, terminated, truncated, info = vec.step(actions)
                counts = info["action_mask"].sum(axis=1)
            return n * rounds / (time.perf_counter() - started)

        print(f"MotionGraphVectorEnv({n}).step with random legal actions: {median_of(runs, vector) / 1e6:.2f} M steps/s "
              f"(one core; budget 2 M)")

    # 4. Zero copy: the graph's largest array viewed, not copied.
    before = rss_mb()
    g = s.graph
    largest = max((v for v in g.values() if isinstance(v, np.ndarray)), key=lambda a: a.nbytes)
    total = sum(v.nbytes for v in g.values() if isinstance(v, np.ndarray))
    touched = float(largest.sum())  # reading it costs nothing either: the memory is the session's
    grown = rss_mb() - before
    print(f"graph views: {total / 1e6:.1f} MB of arrays (largest {largest.nbytes / 1e6:.1f} MB, {largest.shape}); "
          f"resident memory grew {grown:+.2f} MB on viewing and reading them (copies would add {total / 1e6:.1f} MB); "
          f"owndata {largest.flags.owndata}, writeable {largest.flags.writeable} [{touched:.0f}]")


def timed(f):
    started = time.perf_counter()
    f()
    return time.perf_counter() - started


if __name__ == "__main__":
    main()
