#!/usr/bin/env python3
"""Adaptive against uniform hit grids on boxing, with `mgrl train` and `mgrl eval`.

Trains the approach behaviour once (the scenario's own learner), then for each
configuration trains only hit into a copy of that bundle and evaluates the combined policy
with `mgrl eval --trials N --seed S` for each seed. Prints one row per configuration:
vertices (all, free, tied), the hit table's bytes, hit training seconds, success rate and
mean time to hit per seed.

    scripts/adaptive_compare.py [--mgrl build/app/mgrl] [--trials 300] [--seeds 1,2,3]
                                [--only NAME,...] [--json OUT]

Every row is reproducible by hand: the script prints the `mgrl` commands it runs (stderr).
MGRL_DATA and MGRL_CACHE are passed through (set MGRL_CACHE to keep the graph cache apart).
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENARIO = "scenarios/boxing.yaml"


def hit(part, **settings):
    """`--set` flags for the hit behaviour's `part` (discretizer or learner): one per setting
    that is not None, in the order given."""
    return [f"behaviors.hit.{part}.{key}={value}" for key, value in settings.items() if value is not None]


def uniform(angles, distances, heights):
    """Value iteration on the scenario's grid with these vertex counts."""
    return " ".join(hit("learner", type="value_iteration") +
                    hit("discretizer", angles=angles, distances=distances, heights=heights))


def adaptive(cells, max_vertices, split_axes=None, refinement=None, criterion=None, starts=None):
    """Adaptive value iteration up to `max_vertices` on a kd_tree of `cells` (angle, distance,
    height) over the hits' bounds; a setting left None keeps the plug-in's default."""
    angle_cells, distance_cells, height_cells = cells
    return " ".join(hit("discretizer", type="kd_tree", bounds="hits", angle_cells=angle_cells,
                        distance_cells=distance_cells, height_cells=height_cells) +
                    hit("learner", type="adaptive_value_iteration") +
                    hit("discretizer", split_axes=split_axes, refinement=refinement) +
                    hit("learner", max_vertices=max_vertices, criterion=criterion, starts=starts))


def forest(max_vertices, cells, criterion, starts=None):
    """A conforming, longest-axis tree from `cells` (any counts: a forest of root boxes)."""
    return adaptive(cells, max_vertices, split_axes="longest", refinement="conforming", criterion=criterion,
                    starts=starts)


# name -> --set flags (space separated). Equal table rows: 480 and 1,920 vertices.
CONFIGS = {
    "uniform 10x8x6": uniform(10, 8, 6),
    "uniform 20x16x6": uniform(20, 16, 6),
    "adaptive 480 (old: both, round robin)": adaptive((4, 4, 2), 480),
    "adaptive 480 longest": adaptive((4, 4, 2), 480, split_axes="longest"),
    "adaptive 480 longest influence_policy": adaptive((4, 4, 2), 480, split_axes="longest",
                                                      criterion="influence_policy"),
    "adaptive 1920 longest influence_policy": adaptive((8, 8, 4), 1920, split_axes="longest",
                                                       criterion="influence_policy"),
    # Conforming splits: the neighbours around a split leaf's new corners split too, so that
    # those corners are free (discretizers/README.md).
    "adaptive 480 conforming influence_policy": forest(480, (4, 4, 2), "influence_policy"),
    # From the largest power-of-two cells of the uniform grids' proportions within 85 % of the
    # budget (mgrl_bench_adaptive's start): 8 x 8 x 4 cells, 405 vertices.
    "adaptive 480 conforming both 8x8x4": forest(480, (8, 8, 4), "both"),
    # A forest start (kd_tree cells of any count): the uniform grid's cells scaled down to 75 %
    # of the budget (mgrl_bench_adaptive's start since kd_tree has root boxes), refined by
    # the value criterion. The cells are what the bench prints for each budget.
    "uniform 6x5x4": uniform(6, 5, 4),
    "uniform 8x6x5": uniform(8, 6, 5),
    "adaptive 120 forest value 4x3x3": forest(120, (4, 3, 3), "value"),
    "adaptive 240 forest value 6x4x4": forest(240, (6, 4, 4), "value"),
    "adaptive 480 forest value 8x6x4": forest(480, (8, 6, 4), "value"),
    "adaptive 480 forest both 8x6x4": forest(480, (8, 6, 4), "both"),
    "uniform 14x12x6": uniform(14, 12, 6),
    "adaptive 1008 forest value 12x10x4": forest(1008, (12, 10, 4), "value"),
    "adaptive 1920 forest value 17x13x4": forest(1920, (17, 13, 4), "value"),
    # The same with `starts: 3` (the learner also refines from the cells scaled by 0.9 and
    # 0.8, and keeps the tree with the lowest backup gap).
    "adaptive 120 forest value 4x3x3 starts 3": forest(120, (4, 3, 3), "value", starts=3),
    "adaptive 240 forest value 6x4x4 starts 3": forest(240, (6, 4, 4), "value", starts=3),
    "adaptive 480 forest value 8x6x4 starts 3": forest(480, (8, 6, 4), "value", starts=3),
    "adaptive 1008 forest value 12x10x4 starts 3": forest(1008, (12, 10, 4), "value", starts=3),
    "adaptive 1920 forest value 17x13x4 starts 3": forest(1920, (17, 13, 4), "value", starts=3),
    "adaptive 480 conforming both": forest(480, (4, 4, 2), "both"),
}


def run(mgrl, args, env):
    print("+ mgrl " + " ".join(args), file=sys.stderr)
    result = subprocess.run([mgrl] + args, cwd=ROOT, env=env, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"adaptive_compare: `mgrl {' '.join(args)}` failed ({result.returncode}):\n{result.stderr}")
    return json.loads(result.stdout)


def sets(flags):
    out = []
    for flag in flags.split():
        out += ["--set", flag]
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mgrl", default=os.path.join(ROOT, "build/app/mgrl"))
    parser.add_argument("--trials", type=int, default=300)
    parser.add_argument("--seeds", default="1,2,3")
    parser.add_argument("--only", default="", help="comma-separated configuration names (default: all)")
    parser.add_argument("--set", action="append", default=[], help="NAME=FLAGS: add a configuration")
    parser.add_argument("--json", default="", help="also write the rows here")
    args = parser.parse_args()
    configs = dict(CONFIGS)
    if args.only:
        wanted = args.only.split(",")
        configs = {k: v for k, v in configs.items() if k in wanted}
    for item in args.set:
        name, flags = item.split("=", 1)
        configs[name] = flags
    env = dict(os.environ)
    seeds = [int(s) for s in args.seeds.split(",")]
    scratch = tempfile.mkdtemp(prefix="mgrl-adaptive-compare-")
    rows = []
    try:
        base = os.path.join(scratch, "approach")
        run(args.mgrl, ["train", SCENARIO, "--behavior", "approach", "--out", base, "--json"], env)
        for name, flags in configs.items():
            out = os.path.join(scratch, f"run{len(rows)}")
            shutil.copytree(base, out)
            trained = run(args.mgrl, ["train", SCENARIO, "--behavior", "hit", "--out", out, "--json"] + sets(flags),
                          env)
            hit = trained["behaviors"]["hit"]
            vertices = hit["vertices"]
            tied = hit["stats"].get("hanging_vertices", 0)
            row = {"name": name, "flags": flags, "vertices": vertices, "free": vertices - tied, "tied": tied,
                   "table_bytes": hit["table_bytes"], "train_s": hit["seconds"] + hit["tabulate_seconds"],
                   "start": hit["stats"].get("initial_cells"), "seeds": {}}
            for seed in seeds:
                result = run(args.mgrl, ["eval", SCENARIO, "--policy", out, "--trials", str(args.trials), "--seed",
                                         str(seed), "--json"] + sets(flags), env)
                row["seeds"][seed] = {"success": result["success_rate"], "time": result["mean_time_to_hit_s"]}
            rows.append(row)
            print_row(row, seeds)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)


def print_row(row, seeds):
    cells = "  ".join(f"{100 * row['seeds'][s]['success']:5.1f}% {row['seeds'][s]['time']:.2f}s" for s in seeds)
    times = [row["seeds"][s]["time"] for s in seeds]
    start = "x".join(str(c) for c in row["start"]) if row.get("start") else "-"
    print(f"{row['name']:<44} {start:>8} {row['vertices']!s:>6} {row['free']!s:>6} {row['tied']!s:>6} "
          f"{row['table_bytes']!s:>9} {row['train_s'] or 0:7.1f}s  {cells}  mean {sum(times) / len(times):.2f}s",
          flush=True)


if __name__ == "__main__":
    main()
