#!/usr/bin/env python3
"""mpi_value_iteration's sweep time and exchange on this machine for 1, 2 and 4
ranks (real `mpirun`, medians of --repeat runs), the bytes each split of the table would
exchange (build/bench/mgrl_bench_mpi), and a model of the time per sweep on 16 and 64
machines and for a table of 100 GB.

    scripts/mpi_scaling.py [--mgrl build/app/mgrl] [--bench build/bench/mgrl_bench_mpi]
                           [--scenario scenarios/boxing.yaml] [--behavior hit] [--set K=V]...
                           [--ranks 1,2,4] [--repeat 3] [--bandwidth-gbit 10] [--latency-us 20]
                           [--json FILE]

The model (docs/distributed.md): on M machines like this one, a sweep of N entries takes
    N * b / M                         backups, b = this machine's measured seconds a backup
  + B(M) / bandwidth                  the busiest rank's bytes received (counted, not guessed)
  + M * latency                       one message to every other rank
For M beyond the counts, B(M) = 4 N / M * f(M), f the measured fraction of a rank's values
that other ranks back up (about (M - 1) / M). Stated network: --bandwidth-gbit, --latency-us.
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run_train(args, ranks, out):
    command = [args.mgrl, "train", args.scenario, "--behavior", args.behavior, "--json", "--out", out,
               "--set", f"behaviors.{args.behavior}.learner.type=mpi_value_iteration",
               "--set", f"behaviors.{args.behavior}.learner.checkpoint_every=0"]
    for s in args.set:
        command += ["--set", s]
    if args.cache:
        command += ["--cache", args.cache]
    env = dict(os.environ, OMPI_MCA_btl="self,vader", OMPI_MCA_rmaps_base_oversubscribe="1")
    command = ["mpirun", "--allow-run-as-root", "--oversubscribe", "--bind-to", "none", "-np", str(ranks)] + command
    done = subprocess.run(command, capture_output=True, text=True, env=env)
    if done.returncode != 0:
        sys.exit(f"mpi_scaling: {' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
    report = json.loads(done.stdout)["behaviors"][args.behavior]
    shutil.rmtree(out, ignore_errors=True)
    return report


def human_bytes(b):
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if b >= size:
            return f"{b / size:.1f} {unit}"
    return f"{b:.0f} B"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--mgrl", default=os.path.join(ROOT, "build/app/mgrl"))
    p.add_argument("--bench", default=os.path.join(ROOT, "build/bench/mgrl_bench_mpi"))
    p.add_argument("--scenario", default=os.path.join(ROOT, "scenarios/boxing.yaml"))
    p.add_argument("--behavior", default="hit")
    p.add_argument("--set", action="append", default=[])
    p.add_argument("--cache", default="")
    p.add_argument("--ranks", default="1,2,4")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--bandwidth-gbit", type=float, default=10.0)
    p.add_argument("--latency-us", type=float, default=20.0)
    p.add_argument("--json", default="")
    args = p.parse_args()
    ranks = [int(k) for k in args.ranks.split(",")]

    bench = [args.bench, args.scenario, args.behavior, "--ranks", ",".join(str(k) for k in sorted(set(ranks + [16, 64])))]
    for s in args.set:
        bench += ["--set", s]
    counted = subprocess.run(bench, capture_output=True, text=True)
    if counted.returncode != 0:
        sys.exit(f"mpi_scaling: {' '.join(bench)} failed:\n{counted.stderr}")
    counts = json.loads(counted.stdout)
    split = {s["ranks"]: s for s in counts["splits"]}
    N = counts["vertices"] * counts["actions"]
    print(f"{args.behavior} of {os.path.basename(args.scenario)}: {counts['vertices']} vertices x {counts['actions']} "
          f"actions = {N / 1e6:.1f} M entries, table {human_bytes(counts['table_bytes'])}")
    print("bytes received per sweep by the busiest rank, by split:")
    for k in sorted(split):
        s = split[k]
        print(f"  {k:3d} ranks: by graph state {human_bytes(s['by_graph_state']['busiest_rank_bytes']):>9}, "
              f"by vertex block {human_bytes(s['by_vertex_block']['busiest_rank_bytes']):>9}")

    measured = []
    with tempfile.TemporaryDirectory(prefix="mgrl-mpi-scaling-") as scratch:
        for k in ranks:
            runs = [run_train(args, k, os.path.join(scratch, f"np{k}-{i}")) for i in range(args.repeat)]
            sweeps = runs[0]["stats"]["sweeps"]
            per = lambda key: statistics.median(r["stats"][key] for r in runs) / sweeps
            row = {"ranks": k, "sweeps": sweeps,
                   "sweep_seconds": statistics.median(r["seconds"] for r in runs) / sweeps,
                   "backup_seconds_per_sweep": per("backup_seconds_busiest_rank"),
                   "exchange_seconds_per_sweep": per("exchange_seconds_busiest_rank"),
                   "bytes_sent_per_sweep": runs[0]["stats"]["bytes_sent_per_sweep_busiest_rank"],
                   "tabulate_seconds": statistics.median(r["stats"]["tabulate_seconds"] for r in runs)}
            measured.append(row)
    print(f"measured on this machine ({os.cpu_count()} cores, ranks share them), medians of {args.repeat} runs:")
    for r in measured:
        print(f"  {r['ranks']} rank(s): {r['sweep_seconds'] * 1e3:8.1f} ms a sweep (backups "
              f"{r['backup_seconds_per_sweep'] * 1e3:.1f} ms, exchange {r['exchange_seconds_per_sweep'] * 1e3:.1f} ms), "
              f"{human_bytes(r['bytes_sent_per_sweep'])} sent a sweep by the busiest rank, "
              f"tabulated in {r['tabulate_seconds']:.2f} s, {r['sweeps']} sweeps")

    one = next(r for r in measured if r["ranks"] == 1)
    b = one["backup_seconds_per_sweep"] / N  # seconds a backup, this machine's cores
    bandwidth = args.bandwidth_gbit * 1e9 / 8
    latency = args.latency_us * 1e-6
    largest = max(split)
    fraction = split[largest]["by_graph_state"]["busiest_rank_bytes"] / (4 * N / largest)

    def model(entries, machines):
        if machines in split and entries == N:
            received = split[machines]["by_graph_state"]["busiest_rank_bytes"]
        else:
            received = 4 * entries / machines * fraction
        compute = entries * b / machines
        return compute, received / bandwidth, machines * latency

    print(f"model: machines like this one, {args.bandwidth_gbit:g} Gbit/s, {args.latency_us:g} us a message; "
          f"a backup {b * 1e9:.2f} ns here")
    modelled = []
    for entries, label in ((N, "this table"), (100e9 / 4, "a 100 GB table")):
        for machines in (16, 64):
            c, x, l = model(entries, machines)
            # learners/mpi_value_iteration.cpp, bytesPerProcess(): a share of the model,
            # rows and buffers (32 bytes an entry / M), and at rank 0 the whole table (4).
            share, head = entries * 32 / machines, entries * (4 + 32 / machines)
            modelled.append({"table_bytes": 4 * entries, "machines": machines, "compute_seconds": c,
                             "exchange_seconds": x, "latency_seconds": l, "sweep_seconds": c + x + l,
                             "rank0_bytes": head, "other_rank_bytes": share})
            print(f"  {label} ({human_bytes(4 * entries)}) on {machines:2d} machines: {c + x + l:9.3f} s a sweep "
                  f"(backups {c:.3f}, exchange {x:.3f}, latency {l:.4f}); rank 0 holds {human_bytes(head)}, "
                  f"each other rank {human_bytes(share)}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"counts": counts, "measured": measured, "model": modelled,
                       "bandwidth_gbit": args.bandwidth_gbit, "latency_us": args.latency_us}, f, indent=2)


if __name__ == "__main__":
    main()
