"""How mgrl init and mgrl graph scale with the size of the motion library.

    /usr/bin/python3 bench/library_scaling.py [--hours 0.3,1,4] [--mgrl PATH] [--work DIR]
                                              [--keep] [--timeout S] [--json OUT]
                                              [--graph-set KEY=VALUE ...]

For each size in --hours, bench/make_library.py writes a library of that many hours into
WORK/hH/lib (by default the Bandai Namco clips, then time-warped and mirrored copies of
them; 0.3 h is about the clips themselves). Then two steps run, each under
/usr/bin/time -v for its wall time and peak resident memory:

    mgrl init FILE... --name lib --out WORK/hH/lib.yaml --data WORK/hH/lib --force
    mgrl graph WORK/hH/lib.yaml --json --no-cache --cache WORK/hH/cache --data WORK/hH/lib

with every .bvh file of the library passed to init by its path. From graph's JSON come
the states, the actions and the frames in the largest strongly connected component;
mean out-degree is actions per state. graph --json has no per-clip figures, so the share
of each clip category in the component is not measured (the run says so).

init chooses the graph settings (threshold, contact event) for each library anew, so two
sizes may be built with different thresholds; the table shows the threshold used.
--graph-set KEY=VALUE (repeatable) passes --set KEY=VALUE to graph, e.g.
graph.threshold=0.6 to build every size with one threshold.

The growth exponent b of y = a * frames^b is fitted by least squares on log-log for graph
wall time, actions, states, and both steps' wall time and peak memory. A table and the
exponents are printed; --json OUT writes every figure, graph's whole JSON included.

A failing step stops the run with the tail of its stderr (the sizes already measured are
still printed); a step running longer than --timeout seconds (default 1800) is killed
with its whole process group and reported. If the mgrl executable changes on disk during
the run (a rebuild), the run says so, as its figures then mix two builds. WORK defaults
to a temporary folder, deleted at the end unless --keep or a step failed; a --work
folder is kept, and each size's graph cache is deleted unless --keep-cache. On a shared
machine run it niced: nice -n 19 /usr/bin/python3 bench/library_scaling.py ...
"""
import argparse
import json
import math
import os
import pathlib
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
MAKE_LIBRARY = ROOT / "bench" / "make_library.py"
TIME = "/usr/bin/time"
STDERR_TAIL = 15  # lines of a failed step's stderr to show
FITTED = [("graph_s", "graph wall time"), ("actions", "actions"), ("states", "states"),
          ("graph_peak_mb", "graph peak memory"), ("init_s", "init wall time"),
          ("init_peak_mb", "init peak memory")]


class StepFailed(Exception):
    """A step exited non-zero, timed out or printed something unreadable."""


def log(message):
    print(f"library_scaling: {message}", file=sys.stderr, flush=True)


def tail(text, lines=STDERR_TAIL):
    kept = text.rstrip().splitlines()[-lines:]
    return "\n".join("    " + line for line in kept) if kept else "    (nothing on stderr)"


def parse_time_report(text):
    """Wall seconds and peak RSS (MB) from GNU time -v's report."""
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): ([\d:.]+)", text)
    peak = re.search(r"Maximum resident set size \(kbytes\): (\d+)", text)
    if not wall or not peak:
        return None, None
    seconds = 0.0
    for part in wall.group(1).split(":"):
        seconds = seconds * 60 + float(part)
    return seconds, int(peak.group(1)) / 1024.0


def executable_fingerprint(path):
    """Size and modification time of a file: changes when it is rebuilt."""
    stat = os.stat(path)
    return stat.st_size, stat.st_mtime_ns


def run_step(name, command, folder, timeout, measure=True):
    """Run command (under /usr/bin/time -v when measure) in its own process group.

    Returns (stdout, wall seconds, peak MB). Raises StepFailed with the stderr tail on a
    non-zero exit, and after killing the group when the step outlives timeout seconds.
    """
    report = folder / f"{name}.time"
    full = [TIME, "-v", "-o", str(report)] + command if measure else command
    (folder / f"{name}.cmd").write_text(" ".join(full) + "\n")
    log(f"{name}: running ({folder.name})")
    started = time.monotonic()
    process = subprocess.Popen(full, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               start_new_session=True)
    try:
        stdout, stderr = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        stdout, stderr = process.communicate()
        raise StepFailed(f"{name} ({folder.name}) exceeded --timeout {timeout:g} s and was killed; "
                         f"its stderr ended:\n{tail(stderr)}")
    elapsed = time.monotonic() - started
    (folder / f"{name}.out").write_text(stdout)
    (folder / f"{name}.err").write_text(stderr)
    if process.returncode != 0:
        raise StepFailed(f"{name} ({folder.name}) exited with status {process.returncode}; "
                         f"command in {folder / (name + '.cmd')}; its stderr ended:\n{tail(stderr)}")
    wall, peak = elapsed, None
    if measure:
        wall, peak = parse_time_report(report.read_text() if report.exists() else "")
        if wall is None:
            raise StepFailed(f"{name} ({folder.name}): expected /usr/bin/time -v's report in {report}, found none")
    log(f"{name}: {wall:.1f} s" + (f", peak {peak:.0f} MB" if peak is not None else ""))
    return stdout, wall, peak


def generate(hours, folder, args):
    """Write the library with make_library.py; return (folder, files, frames, hours)."""
    library = folder / "lib"
    command = [sys.executable, str(MAKE_LIBRARY), "--hours", f"{hours:g}", "--out", str(library),
               "--seed", str(args.seed), "--force"]
    if args.source:
        command += ["--source", str(args.source)]
    stdout, wall, _ = run_step("make_library", command, folder, args.timeout, measure=False)
    summary = re.search(r"(\d+) files, (\d+) frames, ([\d.]+) hours", stdout)
    if not summary:
        raise StepFailed(f"make_library ({folder.name}): expected a summary line, found {stdout.strip()[-200:]!r}")
    files, frames, written = int(summary.group(1)), int(summary.group(2)), float(summary.group(3))
    return library, files, frames, written, wall


def read_graph_json(stdout, folder):
    try:
        report = json.loads(stdout)
    except json.JSONDecodeError as err:
        raise StepFailed(f"graph ({folder.name}): expected one JSON object on stdout, found unreadable text ({err})")
    missing = [k for k in ("states", "actions", "frames_in_scc", "frames_total") if k not in report]
    if missing:
        raise StepFailed(f"graph ({folder.name}): expected keys {', '.join(missing)} in its JSON, found "
                         f"{', '.join(sorted(report))}")
    return report


def per_clip_figures(report):
    """Keys of the graph JSON that hold per-clip or per-file figures, if any."""
    return [key for key, value in report.items()
            if isinstance(value, (list, dict)) and re.search(r"clip|file", key)]


def measure_size(hours, work, args):
    folder = work / f"h{hours:g}"
    folder.mkdir(parents=True, exist_ok=True)
    library, files, frames, written, generate_s = generate(hours, folder, args)
    paths = sorted(str(p) for p in library.glob("*.bvh"))
    scenario = folder / "lib.yaml"
    _, init_s, init_mb = run_step(
        "init", [args.mgrl, "init", *paths, "--name", "lib", "--out", str(scenario),
                 "--data", str(library), "--force"], folder, args.timeout)
    overrides = [item for setting in args.graph_set for item in ("--set", setting)]
    stdout, graph_s, graph_mb = run_step(
        "graph", [args.mgrl, "graph", str(scenario), "--json", "--no-cache", "--cache", str(folder / "cache"),
                  "--data", str(library), *overrides], folder, args.timeout)
    report = read_graph_json(stdout, folder)
    if not args.keep_cache:
        shutil.rmtree(folder / "cache", ignore_errors=True)
    states, actions = report["states"], report["actions"]
    return {
        "hours": written,
        "hours_asked": hours,
        "files": files,
        "frames": frames,
        "generate_s": round(generate_s, 2),
        "init_s": init_s,
        "init_peak_mb": round(init_mb, 1),
        "graph_s": graph_s,
        "graph_peak_mb": round(graph_mb, 1),
        "graph_reported_seconds": report.get("seconds"),
        "graph_build_seconds": report.get("build_seconds"),
        "states": states,
        "actions": actions,
        "transitions": report.get("transitions"),
        "mean_out_degree": round(actions / states, 3) if states else None,
        "frames_in_component": report["frames_in_scc"],
        "frames_loaded": report["frames_total"],
        "component_share": round(report["frames_in_scc"] / report["frames_total"], 4) if report["frames_total"] else None,
        "scenario_graph": scenario_graph_settings(scenario),
        "graph_set": list(args.graph_set),
        "per_clip_keys": per_clip_figures(report),
        "graph_json": report,
    }


def scenario_graph_settings(scenario):
    """The graph settings init chose (threshold, event), from the scenario it wrote."""
    settings = {}
    try:
        text = scenario.read_text()
    except OSError:
        return settings
    block = re.search(r"^graph:\n((?:[ \t]+.*\n|[ \t]*#.*\n|\n)*)", text, re.MULTILINE)
    if block:
        for line in block.group(1).splitlines():
            found = re.match(r"^  (\w+):\s*([^#\s][^#]*?)\s*(?:#.*)?$", line)
            if found:
                settings[found.group(1)] = found.group(2).strip('"')
    return settings


def fit_exponent(frames, values):
    """b of y = a * frames^b by least squares on log-log; None with fewer than 2 usable sizes."""
    pairs = [(f, v) for f, v in zip(frames, values) if f and v and f > 0 and v > 0]
    if len({f for f, _ in pairs}) < 2:
        return None
    x = np.log([f for f, _ in pairs])
    y = np.log([v for _, v in pairs])
    slope, _ = np.polyfit(x, y, 1)
    return float(slope)


def print_table(rows, exponents):
    for row in rows:
        row["threshold"] = row["scenario_graph"].get("threshold", "?")
        for setting in row["graph_set"]:
            key, _, value = setting.partition("=")
            if key == "graph.threshold":
                row["threshold"] = value
    columns = [("hours", "{:.2f}"), ("files", "{:d}"), ("frames", "{:d}"), ("threshold", "{}"), ("init_s", "{:.1f}"),
               ("init_peak_mb", "{:.0f}"), ("graph_s", "{:.1f}"), ("graph_peak_mb", "{:.0f}"),
               ("states", "{:d}"), ("actions", "{:d}"), ("mean_out_degree", "{:.1f}"),
               ("component_share", "{:.3f}")]
    headers = ["hours", "files", "frames", "thresh", "init s", "init MB", "graph s", "graph MB", "states",
               "actions", "out-deg", "in comp"]
    cells = [[fmt.format(row[key]) if row[key] is not None else "-" for key, fmt in columns] for row in rows]
    widths = [max(len(h), *(len(c[i]) for c in cells)) for i, h in enumerate(headers)]
    print("  ".join(h.rjust(w) for h, w in zip(headers, widths)))
    for c in cells:
        print("  ".join(v.rjust(w) for v, w in zip(c, widths)))
    print()
    print("growth exponent b of y = a * frames^b (least squares on log-log):")
    for key, label in FITTED:
        value = exponents.get(key)
        print(f"  {label:20s} " + (f"{value:.2f}" if value is not None else "- (needs two sizes)"))
    settings = [f"{r['hours']:.2f} h: " + ", ".join(f"{k} {v}" for k, v in r["scenario_graph"].items())
                for r in rows if r["scenario_graph"]]
    if settings:
        print("graph settings init chose: " + "; ".join(settings))
    if rows and rows[0]["graph_set"]:
        print("graph run with --set " + " --set ".join(rows[0]["graph_set"]))


def parse_arguments(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", default="0.3,1,4", help="library sizes in hours, comma-separated (default 0.3,1,4)")
    parser.add_argument("--mgrl", default=os.environ.get("MGRL", str(ROOT / "build" / "app" / "mgrl")),
                        help="mgrl executable (default: $MGRL, else build/app/mgrl of this tree)")
    parser.add_argument("--work", type=pathlib.Path, help="scratch folder (default: a temporary one)")
    parser.add_argument("--keep", action="store_true", help="keep the temporary scratch folder")
    parser.add_argument("--keep-cache", action="store_true", help="keep each size's graph cache (large)")
    parser.add_argument("--timeout", type=float, default=1800, help="seconds a single step may take (default 1800)")
    parser.add_argument("--json", type=pathlib.Path, help="write every figure to this JSON file")
    parser.add_argument("--seed", type=int, default=1, help="make_library.py's seed (default 1)")
    parser.add_argument("--source", type=pathlib.Path, help="make_library.py's source folder (default its own)")
    parser.add_argument("--graph-set", action="append", default=[], metavar="KEY=VALUE",
                        help="pass --set KEY=VALUE to mgrl graph, e.g. graph.threshold=0.6 (repeatable)")
    args = parser.parse_args(argv)
    try:
        args.sizes = [float(h) for h in args.hours.split(",") if h.strip()]
    except ValueError:
        parser.error(f"--hours: expected comma-separated numbers, found {args.hours!r}")
    if not args.sizes or any(not (math.isfinite(h) and h > 0) for h in args.sizes):
        parser.error(f"--hours: expected positive numbers of hours, found {args.hours!r}")
    if not (args.timeout > 0):
        parser.error(f"--timeout: expected a positive number of seconds, found {args.timeout:g}")
    if not (os.path.isfile(args.mgrl) and os.access(args.mgrl, os.X_OK)):
        parser.error(f"--mgrl: expected an executable, found {'a non-executable file' if os.path.exists(args.mgrl) else 'nothing'} at {args.mgrl}")
    if not os.access(TIME, os.X_OK):
        parser.error(f"expected GNU time at {TIME}, found nothing")
    return args


def mgrl_version(mgrl):
    try:
        return subprocess.run([mgrl, "--version"], capture_output=True, text=True, timeout=30).stdout.strip()
    except (OSError, subprocess.TimeoutExpired):
        return None


def main(argv=None):
    args = parse_arguments(argv)
    temporary = args.work is None
    work = pathlib.Path(tempfile.mkdtemp(prefix="library_scaling.")) if temporary else args.work
    work.mkdir(parents=True, exist_ok=True)
    log(f"work folder {work}")
    started = time.monotonic()
    fingerprint = executable_fingerprint(args.mgrl)
    rows, error, rebuilt = [], None, []
    try:
        for hours in sorted(args.sizes):
            rows.append(measure_size(hours, work, args))
            if executable_fingerprint(args.mgrl) != fingerprint:
                rebuilt.append(hours)
                fingerprint = executable_fingerprint(args.mgrl)
    except StepFailed as failure:
        error = str(failure)
    total_s = time.monotonic() - started

    frames = [r["frames"] for r in rows]
    exponents = {key: fit_exponent(frames, [r[key] for r in rows]) for key, _ in FITTED}
    if rows:
        print_table(rows, exponents)
        keys = rows[-1]["per_clip_keys"]
        if keys:
            print(f"graph --json has per-clip keys ({', '.join(keys)}), not read by this benchmark")
        else:
            print("per-category share of frames in the component: not measured "
                  "(graph --json reports only the whole library's frames_in_scc)")
    if rebuilt:
        print(f"warning: {args.mgrl} changed on disk while measuring the "
              f"{', '.join(f'{h:g} h' for h in rebuilt)} library; its figures may mix two builds")
    print(f"total run time {total_s:.0f} s")
    if args.json:
        result = {"sizes": rows, "exponents": exponents, "total_seconds": round(total_s, 1),
                  "mgrl": args.mgrl, "mgrl_version": mgrl_version(args.mgrl), "seed": args.seed,
                  "per_category_component_share": None,
                  "per_category_note": "graph --json reports no per-clip figures",
                  "mgrl_changed_during_hours": rebuilt,
                  "error": error}
        args.json.write_text(json.dumps(result, indent=2) + "\n")
        log(f"wrote {args.json}")
    if temporary and not args.keep and not error:
        shutil.rmtree(work, ignore_errors=True)
    elif temporary:
        log(f"kept {work}" + (" (a step failed; its output is there)" if error else ""))
    if error:
        print(f"library_scaling: error: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
