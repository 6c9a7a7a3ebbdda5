#!/usr/bin/env python3
"""Keeps the sample outputs and the figures in README.md and the docs true to what `mgrl` prints.

Two kinds of markers. A sample output is a fenced block right after a line

    <!-- mgrl-output: simulate scenarios/boxing.yaml --avatars 30 --seconds 33.3 -->

naming the `mgrl` arguments that print it (run from the repository root, stdout only). A
figure in the prose is checked by a line

    <!-- mgrl-figure: ARGS ; ARGS ... => EXPECTED | EXPECTED ... -->

that runs each `mgrl ARGS` in turn (say a `train` with some --set flags, then the `eval`
that reads its bundle) and looks in the last one's stdout for each EXPECTED text, e.g.
`success rate 95.0 %`: same words, numbers within the tolerance below. EXPECTED may give a
range, `93..96`, for a figure the prose states as a range. Put the marker right after the
paragraph whose figures it checks, and keep the two in step.

The markers are read from README.md, every page in docs/ and scenarios/README.md (or from
the one file --readme names).

Before anything runs, the boxing scenario is trained with its own budgets, as the README
tells a user to; every command shares that cache (graph and bundles), so a figure's train
is reused by a later figure with the same settings.

    scripts/readme_outputs.py --update [--mgrl build/app/mgrl]   rewrite the sample blocks from real runs
    scripts/readme_outputs.py --check  [--mgrl build/app/mgrl]   fail on any difference, saying where

What is compared: every seeded, deterministic number (success rates, times to hit in
simulated seconds, hit counts, states, actions, frames, table sizes) must agree within 1 %
of its value or one unit of its last printed digit, whichever is larger. Wall-clock
timings and rates (`0.56 s` of training, `7.47 Mdecisions/s`, `in 3.5 ms`) and bundle
hashes are masked: they differ from machine to machine. Cache paths print as
~/.cache/mgrl whatever MGRL_CACHE is.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

MARKER = re.compile(r"^<!-- mgrl-output: (.*) -->$")
FIGURE = re.compile(r"^\s*<!-- mgrl-figure: (.*) => (.*) -->$")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NUMBER = r"-?\d+(?:\.\d+)?"
RELATIVE = 0.01  # the tolerance: 1 % of the value ...

# Wall-clock figures, masked: each pattern's group 1 is the number.
WALL_CLOCK = [
    re.compile(r"(" + NUMBER + r")\s?[kMG]?(?:updates|decisions|avatar-frames|frames|steps)/s\b"),
    re.compile(r"\bin (" + NUMBER + r"\s?(?:ms|s|us|µs))(?=\W|$)"),  # the unit too: 3.5 ms on one machine, 0.10 s on another
    re.compile(r"\bupdates\s+(" + NUMBER + r") s\b"),  # train's seconds column
    re.compile(r"^build\s+(" + NUMBER + r") s\b"),  # graph: the build (or cache read) time
]


def unit(text):
    """One unit of the last printed digit: 0.1 for "95.0", 1 for "605"."""
    return 10.0 ** -len(text.split(".")[1]) if "." in text else 1.0


def agree(documented, actual):
    """`actual` is within the tolerance of the README's `documented` number (a string)."""
    if ".." in documented:
        low, high = documented.split("..")
        return float(low) - unit(low) <= actual <= float(high) + unit(high)
    value = float(documented)
    return abs(actual - value) <= max(RELATIVE * abs(value), unit(documented)) + 1e-12


def masked(line):
    """The line with hashes and wall-clock numbers replaced by words, so they are neither
    compared nor counted as numbers."""
    line = re.sub(r"-[0-9a-f]{8}\b", "-HASH", line)
    for pattern in WALL_CLOCK:
        line = pattern.sub(lambda m: m.group(0).replace(m.group(1), "WALL", 1), line)
    # A rate's prefix follows the machine's speed (1.96 Mupdates/s, 463.0 kupdates/s).
    return re.sub(r"WALL(\s?)[kMG](?=[A-Za-z-]+/s\b)", r"WALL\1", line)


def split(line):
    """(the line's words with each number as a NUL and spacing collapsed, its numbers as text)."""
    line = masked(line)
    numbers = re.findall(NUMBER + r"(?:\.\." + NUMBER + r")?", line)
    words = re.sub(NUMBER + r"(?:\.\." + NUMBER + r")?", "\0", line)
    return re.sub(r"\s+", " ", words).strip(), numbers  # columns pad numbers to their width


def compare_lines(documented, actual):
    """None if the lines agree, else what differs."""
    dw, dn = split(documented)
    aw, an = split(actual)
    if dw != aw:
        return "the words differ"
    wrong = [f"{d} (now {a})" for d, a in zip(dn, an) if not agree(d, float(a))]
    return ("numbers out of tolerance: " + ", ".join(wrong)) if wrong else None


def find_figure(expected, output):
    """None if some line of `output` holds `expected` (words equal, numbers within the
    tolerance), else what was found instead."""
    words, numbers = split(expected)
    pattern = ("(" + NUMBER + ")").join(r"\s+".join(re.escape(w) for w in piece.split(" ")) for piece in words.split("\0"))
    near = []
    for line in output:
        for m in re.finditer(pattern, masked(line)):
            actual = [float(g) for g in m.groups()]
            if all(agree(d, a) for d, a in zip(numbers, actual)):
                return None
            near.append(m.group(0))
    return f"found {' / '.join(near)}" if near else "found no line with those words"


def run(mgrl, args, cache, data):
    env = dict(os.environ, MGRL_CACHE=cache, MGRL_DATA=data)
    started = time.monotonic()
    result = subprocess.run([mgrl] + args.split(), cwd=ROOT, env=env, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"readme_outputs: `mgrl {args}` failed with exit code {result.returncode}:\n{result.stderr}")
    print(f"readme_outputs: mgrl {args} ({time.monotonic() - started:.1f} s)", file=sys.stderr)
    return result.stdout.replace(cache, "~/.cache/mgrl").rstrip("\n").split("\n")


def blocks(lines, name="README.md"):
    """(marker index, args, first line of the block's body, index of its closing fence)."""
    found = []
    for i, line in enumerate(lines):
        m = MARKER.match(line)
        if not m:
            continue
        if i + 1 >= len(lines) or not lines[i + 1].startswith("```"):
            sys.exit(f"{name}:{i + 1}: expected a fenced block right after the mgrl-output marker, found none")
        end = i + 2
        while end < len(lines) and not lines[end].startswith("```"):
            end += 1
        if end == len(lines):
            sys.exit(f"{name}:{i + 2}: expected the block to be closed with ```, found the end of the file")
        found.append((i, m.group(1), i + 2, end))
    return found


def figures(lines, name="README.md"):
    """(line index, [mgrl args per command], [expected texts])."""
    found = []
    for i, line in enumerate(lines):
        if not line.lstrip().startswith("<!-- mgrl-figure:"):
            continue
        m = FIGURE.match(line)
        if not m:
            sys.exit(f"{name}:{i + 1}: expected <!-- mgrl-figure: ARGS ; ARGS => EXPECTED | EXPECTED -->, "
                     f"found {line!r}")
        commands = [c.strip() for c in m.group(1).split(" ; ") if c.strip()]
        expected = [e.strip() for e in m.group(2).split(" | ") if e.strip()]
        if not commands or not expected:
            sys.exit(f"{name}:{i + 1}: expected at least one command and one expected text, found {line!r}")
        found.append((i, commands, expected))
    return found


def documents():
    """README.md, the docs' pages and the scenario keys' page: where markers may be."""
    docs = os.path.join(ROOT, "docs")
    pages = sorted(os.path.join(docs, f) for f in os.listdir(docs) if f.endswith(".md"))
    return [os.path.join(ROOT, "README.md"), *pages, os.path.join(ROOT, "scenarios", "README.md")]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--update", action="store_true")
    mode.add_argument("--check", action="store_true")
    parser.add_argument("--mgrl", default=os.path.join(ROOT, "build", "app", "mgrl"))
    parser.add_argument("--readme", default=None, help=argparse.SUPPRESS)  # one file only (the rules' test)
    parser.add_argument("--data", default=os.environ.get("MGRL_DATA", os.path.join(ROOT, "..", "shared", "mocap")))
    options = parser.parse_args()

    # (path, name, lines, blocks, figures) of every file with markers.
    files = []
    for path in [options.readme] if options.readme else documents():
        with open(path) as f:
            lines = f.read().split("\n")
        name = os.path.relpath(path, ROOT) if not options.readme else os.path.basename(path)
        found, stated = blocks(lines, name), figures(lines, name)
        if found or stated:
            files.append((path, name, lines, found, stated))
    if not any(found for _, _, _, found, _ in files):
        sys.exit("readme_outputs: expected mgrl-output markers in README.md or docs/, found none")
    with tempfile.TemporaryDirectory(prefix="mgrl-readme-") as cache:
        print("readme_outputs: training the boxing scenario (about 20 s)", file=sys.stderr)
        run(options.mgrl, "train scenarios/boxing.yaml", cache, options.data)
        # A `train` that an earlier figure ran with the same arguments is not run again: its
        # bundle is in the shared cache already (a bundle is found by the scenario and its
        # settings), and a second run would write the same tables.
        trained = {}

        def run_figure(args):
            if not args.startswith("train "):
                return run(options.mgrl, args, cache, options.data)
            if args not in trained:
                trained[args] = run(options.mgrl, args, cache, options.data)
            return trained[args]

        results = []
        for path, name, lines, found, stated in files:
            outputs = [run(options.mgrl, args, cache, options.data) for _, args, _, _ in found]
            figure_outputs = [[run_figure(args) for args in commands][-1] for _, commands, _ in stated]
            results.append((outputs, figure_outputs))

    problems = 0
    samples = figures_checked = 0
    for (path, name, lines, found, stated), (outputs, figure_outputs) in zip(files, results):
        samples += len(found)
        figures_checked += sum(len(e) for _, _, e in stated)
        if options.update:
            for (_, _, begin, end), output in reversed(list(zip(found, outputs))):
                lines[begin:end] = output
            tmp = path + ".tmp"
            with open(tmp, "w") as f:
                f.write("\n".join(lines))
            os.replace(tmp, path)
            print(f"readme_outputs: rewrote {len(found)} blocks of {name}; the figures (mgrl-figure) are edited "
                  f"by hand", file=sys.stderr)
            continue
        for (marker, args, begin, end), output in zip(found, outputs):
            documented = lines[begin:end]
            why = (f"{len(documented)} lines in the text, {len(output)} from the program"
                   if len(documented) != len(output) else
                   next((f"line {k + 1}: {w}" for k, (d, o) in enumerate(zip(documented, output))
                         if (w := compare_lines(d, o))), None))
            if why:
                problems += 1
                print(f"{name}:{begin + 1}: the sample output of `mgrl {args}` no longer matches the program's "
                      f"({why}):", file=sys.stderr)
                print("  text:    " + "\n  text:    ".join(documented), file=sys.stderr)
                print("  program: " + "\n  program: ".join(output), file=sys.stderr)
        for (marker, commands, expected), output in zip(stated, figure_outputs):
            for text in expected:
                why = find_figure(text, output)
                if why:
                    problems += 1
                    print(f"{name}:{marker + 1}: the figure '{text}' no longer holds for `mgrl {commands[-1]}`: {why}",
                          file=sys.stderr)
    names = ", ".join(name for _, name, _, _, _ in files)
    if problems:
        sys.exit(f"readme_outputs: {problems} outputs or figures in {names} are stale (tolerance: "
                 f"{RELATIVE:.0%} or one unit of the last digit; timings are not compared): update the text, "
                 f"or run scripts/readme_outputs.py --update for the sample blocks")
    print(f"readme_outputs: the {samples} sample outputs and {figures_checked} figures in {names} match the "
          f"program's", file=sys.stderr)


if __name__ == "__main__":
    main()
