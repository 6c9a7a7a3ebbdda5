#!/usr/bin/env python3
"""Keeps the sample outputs in README.md true to what `mgrl` prints.

A sample output in the README is a fenced block right after a marker line

    <!-- mgrl-output: simulate scenarios/boxing.yaml --avatars 30 --seconds 33.3 -->

naming the `mgrl` arguments that print it (run from the repository root, stdout only).
Before the blocks run, the boxing scenario is trained with its own budgets, as the README
tells a user to, so every block sees the same trained policy.

    scripts/readme_outputs.py --update [--mgrl build/app/mgrl]   rewrite the blocks from real runs
    scripts/readme_outputs.py --check  [--mgrl build/app/mgrl]   fail if a block's lines differ in
        anything but their numbers (a line added, dropped or reworded), saying which

Numbers are left out of the check: timings and rates differ from run to run and machine to
machine. Cache paths print as ~/.cache/mgrl whatever MGRL_CACHE is.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

MARKER = re.compile(r"^<!-- mgrl-output: (.*) -->$")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def shape(line):
    line = re.sub(r"-[0-9a-f]{8}\b", "-HASH", line)
    # A rate's prefix follows the machine's speed as its digits do (1.96 Mupdates/s here,
    # 463.0 kupdates/s on a slower machine; 8.66 Mavatar-frames/s, 975.1 kavatar-frames/s).
    line = re.sub(r"(\d\s?)[kMG](?=[A-Za-z-]+/s\b)", r"\1", line)
    line = re.sub(r"-?\d+(\.\d+)?", "N", line)
    return re.sub(r"\s+", " ", line).strip()  # columns pad numbers to their width


def run(mgrl, args, cache, data):
    env = dict(os.environ, MGRL_CACHE=cache, MGRL_DATA=data)
    result = subprocess.run([mgrl] + args.split(), cwd=ROOT, env=env, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"readme_outputs: `mgrl {args}` failed with exit code {result.returncode}:\n{result.stderr}")
    return result.stdout.replace(cache, "~/.cache/mgrl").rstrip("\n").split("\n")


def blocks(lines):
    """(marker index, args, first line of the block's body, index of its closing fence)."""
    found = []
    for i, line in enumerate(lines):
        m = MARKER.match(line)
        if not m:
            continue
        if i + 1 >= len(lines) or not lines[i + 1].startswith("```"):
            sys.exit(f"README.md:{i + 1}: expected a fenced block right after the mgrl-output marker, found none")
        end = i + 2
        while end < len(lines) and not lines[end].startswith("```"):
            end += 1
        if end == len(lines):
            sys.exit(f"README.md:{i + 2}: expected the block to be closed with ```, found the end of the file")
        found.append((i, m.group(1), i + 2, end))
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--update", action="store_true")
    mode.add_argument("--check", action="store_true")
    parser.add_argument("--mgrl", default=os.path.join(ROOT, "build", "app", "mgrl"))
    parser.add_argument("--data", default=os.environ.get("MGRL_DATA", os.path.join(ROOT, "..", "shared", "mocap")))
    options = parser.parse_args()

    path = os.path.join(ROOT, "README.md")
    with open(path) as f:
        lines = f.read().split("\n")
    found = blocks(lines)
    if not found:
        sys.exit("readme_outputs: expected mgrl-output markers in README.md, found none")
    with tempfile.TemporaryDirectory(prefix="mgrl-readme-") as cache:
        print("readme_outputs: training the boxing scenario (about 20 s)", file=sys.stderr)
        run(options.mgrl, "train scenarios/boxing.yaml", cache, options.data)
        outputs = [run(options.mgrl, args, cache, options.data) for _, args, _, _ in found]

    if options.update:
        for (_, _, begin, end), output in reversed(list(zip(found, outputs))):
            lines[begin:end] = output
        tmp = path + ".tmp"
        with open(tmp, "w") as f:
            f.write("\n".join(lines))
        os.replace(tmp, path)
        print(f"readme_outputs: rewrote {len(found)} blocks of README.md", file=sys.stderr)
        return
    problems = 0
    for (marker, args, begin, end), output in zip(found, outputs):
        documented = lines[begin:end]
        if [shape(l) for l in documented] != [shape(l) for l in output]:
            problems += 1
            print(f"README.md:{begin + 1}: the sample output of `mgrl {args}` no longer matches the program's:",
                  file=sys.stderr)
            print("  README:  " + "\n  README:  ".join(documented), file=sys.stderr)
            print("  program: " + "\n  program: ".join(output), file=sys.stderr)
    if problems:
        sys.exit(f"readme_outputs: {problems} sample outputs are stale: run scripts/readme_outputs.py --update")
    print(f"readme_outputs: the {len(found)} sample outputs in README.md match the program's", file=sys.stderr)


if __name__ == "__main__":
    main()
