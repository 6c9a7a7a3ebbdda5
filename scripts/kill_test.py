#!/usr/bin/env python3
"""Kill tests: SIGKILL `mgrl train`, `mgrl graph` and `mgrl simulate --bvh-out`
at every rename of their replacing writes and at random moments, and check the rule:

  after a kill, each output is the previous complete result, or the new complete result
  (never missing once it existed, never a mix, never half written); the next run (plain or
  `train --resume`) ends with the result of an uninterrupted run of the same seed, byte for
  byte (tables, BVH, events; manifests too, but for timings, pids and seals); and after it
  nothing the killed runs left is still there (`<out>.tmp-PID-N`, `<out>.old-PID-N`,
  `<out>.checkpoints/`, `.mgrl-simulate-PID`, `.<out>.probe-PID`).

Kills at a rename use a tiny LD_PRELOAD shim, compiled here with the C compiler into a
temporary folder: it wraps rename, renameat and renameat2 and raises SIGKILL just before or
just after the N-th call (MGRL_KILL_RENAME_AT=N, MGRL_KILL_RENAME_PHASE=before|after); a
first run of each job with MGRL_KILL_RENAME_LOG=FILE counts the calls. Random kills come
after a delay drawn over the job's measured duration.

  scripts/kill_test.py build/app/mgrl                       # the full run (220 kills)
  scripts/kill_test.py build/app/mgrl --runs 300 --seed 7
  scripts/kill_test.py build/app/mgrl --quick               # a few kills, well under a minute

Exit status 0 if nothing was found, 1 with findings (each printed), 2 on a setup error.
Python 3 standard library only; the motion capture from MGRL_DATA or ../shared/mocap.
"""

import argparse
import hashlib
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path

SHIM_C = r"""
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static long killAt = 0;
static int killAfter = 0;
static int logFd = -1;
static long calls = 0;
static const char* unlinkMatch = 0;

__attribute__((constructor)) static void setUp(void) {
  const char* s = getenv("MGRL_KILL_RENAME_AT");
  if (s) killAt = atol(s);
  s = getenv("MGRL_KILL_RENAME_PHASE");
  if (s && strcmp(s, "after") == 0) killAfter = 1;
  s = getenv("MGRL_KILL_RENAME_LOG");
  if (s) logFd = open(s, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  unlinkMatch = getenv("MGRL_KILL_UNLINK_MATCH");
  if (unlinkMatch && !*unlinkMatch) unlinkMatch = 0;
}

/* MGRL_KILL_UNLINK_MATCH=TEXT: SIGKILL just before removing a file whose path holds TEXT
   (a file made only to be removed again, like train's writability probe). */
static void removing(const char* path) {
  if (unlinkMatch && path && strstr(path, unlinkMatch)) kill(getpid(), SIGKILL);
}

int unlink(const char* path) {
  static int (*real)(const char*);
  if (!real) real = (int (*)(const char*))dlsym(RTLD_NEXT, "unlink");
  removing(path);
  return real(path);
}

int unlinkat(int dir, const char* path, int flags) {
  static int (*real)(int, const char*, int);
  if (!real) real = (int (*)(int, const char*, int))dlsym(RTLD_NEXT, "unlinkat");
  removing(path);
  return real(dir, path, flags);
}

int remove(const char* path) {
  static int (*real)(const char*);
  if (!real) real = (int (*)(const char*))dlsym(RTLD_NEXT, "remove");
  removing(path);
  return real(path);
}

static void say(const char* text) {
  if (logFd < 0) return;
  ssize_t ignored = write(logFd, text, strlen(text));
  (void)ignored;
}

static long enter(const char* fn, const char* from, const char* to) {
  long n = __atomic_add_fetch(&calls, 1, __ATOMIC_SEQ_CST);
  char line[8192];
  snprintf(line, sizeof line, "%ld %s %s -> %s", n, fn, from, to);
  say(line);
  if (n == killAt && !killAfter) kill(getpid(), SIGKILL);
  return n;
}

static void leave(long n, int result, int error) {
  char line[64];
  snprintf(line, sizeof line, " = %d (errno %d)\n", result, result == 0 ? 0 : error);
  say(line);
  if (n == killAt && killAfter) kill(getpid(), SIGKILL);
}

int rename(const char* from, const char* to) {
  static int (*real)(const char*, const char*);
  if (!real) real = (int (*)(const char*, const char*))dlsym(RTLD_NEXT, "rename");
  long n = enter("rename", from, to);
  int r = real(from, to);
  int e = errno;
  leave(n, r, e);
  errno = e;
  return r;
}

int renameat(int fromDir, const char* from, int toDir, const char* to) {
  static int (*real)(int, const char*, int, const char*);
  if (!real) real = (int (*)(int, const char*, int, const char*))dlsym(RTLD_NEXT, "renameat");
  long n = enter("renameat", from, to);
  int r = real(fromDir, from, toDir, to);
  int e = errno;
  leave(n, r, e);
  errno = e;
  return r;
}

int renameat2(int fromDir, const char* from, int toDir, const char* to, unsigned flags) {
  static int (*real)(int, const char*, int, const char*, unsigned);
  if (!real) real = (int (*)(int, const char*, int, const char*, unsigned))dlsym(RTLD_NEXT, "renameat2");
  long n = enter(flags ? "renameat2-exchange" : "renameat2", from, to);
  int r = real(fromDir, from, toDir, to, flags);
  int e = errno;
  leave(n, r, e);
  errno = e;
  return r;
}
"""

# Manifest members that differ between two runs of the same inputs: timings, the writer's
# pid and the clock, and the seals that cover them (a seal is checked by mgrl itself on the
# next run: a graph bundle found whole must be reused, not rebuilt).
VOLATILE = {"seconds", "updates_per_second", "tabulate_seconds", "build_seconds", "time_utc", "pid", "resumed"}
LEFTOVER = [
    (re.compile(r"\.(tmp|old)-\d+-\d+$"), "a killed writer's temporary or replaced bundle"),
    (re.compile(r"^\.mgrl-simulate-\d+$"), "a killed simulate's scratch folder"),
    (re.compile(r"\.probe-\d+$"), "a killed train's writability probe"),
    (re.compile(r"\.checkpoints$"), "checkpoints after a finished run"),
]


def normalize(value, top=True):
    if isinstance(value, dict):
        out = {}
        for key, item in value.items():
            if key in VOLATILE or (top and key == "hash"):
                continue
            if key == "curve" and isinstance(item, list):
                # [updates, seconds, residual, mean_residual]: all but the seconds.
                out[key] = [[x for i, x in enumerate(row) if i != 1] if isinstance(row, list) else row for row in item]
                continue
            out[key] = normalize(item, False)
        return out
    if isinstance(value, list):
        return [normalize(item, False) for item in value]
    return value


def snapshot(path):
    """What a result is, for comparison: None if absent; for a folder, each file's digest and
    the normalized manifest; for a file, its digest. 'unreadable: ...' if a manifest does not
    parse (a wrong result whatever the references say)."""
    path = Path(path)
    if not path.exists() and not path.is_symlink():
        return None
    if path.is_file():
        return ("file", hashlib.sha256(path.read_bytes()).hexdigest())
    entries = {}
    for child in sorted(path.iterdir()):
        if child.is_dir():
            entries[child.name] = ("dir", snapshot(child))
        elif child.name in ("manifest.json", "state.json"):
            try:
                entries[child.name] = ("json", json.dumps(normalize(json.loads(child.read_text())), sort_keys=True))
            except (ValueError, UnicodeDecodeError) as e:
                entries[child.name] = ("unreadable", str(e))
        else:
            entries[child.name] = ("file", hashlib.sha256(child.read_bytes()).hexdigest())
    return ("dir", tuple(sorted(entries.items())))


def leftovers(root):
    found = []
    for dirpath, dirnames, filenames in os.walk(root):
        for name in dirnames + filenames:
            for pattern, what in LEFTOVER:
                if pattern.search(name):
                    found.append(f"{os.path.relpath(os.path.join(dirpath, name), root)} ({what})")
    return sorted(found)


def copy_result(source, destination):
    destination = Path(destination)
    if destination.is_dir() and not destination.is_symlink():
        shutil.rmtree(destination)
    elif destination.exists() or destination.is_symlink():
        destination.unlink()
    if source is None:
        return
    destination.parent.mkdir(parents=True, exist_ok=True)
    if Path(source).is_dir():
        shutil.copytree(source, destination)
    else:
        shutil.copy2(source, destination)


class Runner:
    def __init__(self, mgrl, shim, data, verbose):
        self.mgrl = str(Path(mgrl).resolve())
        self.shim = shim
        self.data = data
        self.verbose = verbose

    def run(self, args, cwd, kill_rename=None, kill_delay=None, count_log=None, kill_unlink=None, timeout=600):
        """Runs mgrl; returns (returncode, stdout, stderr, seconds). returncode is -9 when
        killed. kill_rename = (n, 'before'|'after'); kill_unlink = text of a path whose
        removal is killed."""
        env = dict(os.environ)
        if self.data:
            env["MGRL_DATA"] = self.data
        for name in ("MGRL_EXIT_AFTER_CHECKPOINTS", "MGRL_STOP_AFTER_CHECKPOINTS", "MGRL_CACHE",
                     "MGRL_KILL_RENAME_AT", "MGRL_KILL_RENAME_PHASE", "MGRL_KILL_RENAME_LOG",
                     "MGRL_KILL_UNLINK_MATCH"):
            env.pop(name, None)
        if kill_unlink:
            env["MGRL_KILL_UNLINK_MATCH"] = kill_unlink
        if kill_rename or count_log or kill_unlink:
            env["LD_PRELOAD"] = self.shim + (" " + env["LD_PRELOAD"] if env.get("LD_PRELOAD") else "")
        if kill_rename:
            env["MGRL_KILL_RENAME_AT"] = str(kill_rename[0])
            env["MGRL_KILL_RENAME_PHASE"] = kill_rename[1]
        if count_log:
            env["MGRL_KILL_RENAME_LOG"] = str(count_log)
        command = [self.mgrl] + [str(a) for a in args]
        if self.verbose:
            print("   $", " ".join(command), f"(kill at rename {kill_rename})" if kill_rename else
                  f"(kill after {kill_delay:.2f} s)" if kill_delay is not None else "", flush=True)
        start = time.monotonic()
        with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
            process = subprocess.Popen(command, cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=out, stderr=err)
            try:
                process.wait(timeout=kill_delay if kill_delay is not None else timeout)
            except subprocess.TimeoutExpired:
                if kill_delay is None:
                    process.kill()
                    process.wait()
                    raise RuntimeError(f"mgrl {args[0]} ran over {timeout} s")
                os.kill(process.pid, signal.SIGKILL)
                process.wait()
            seconds = time.monotonic() - start
            out.seek(0)
            err.seek(0)
            return process.returncode, out.read().decode(errors="replace"), err.read().decode(errors="replace"), seconds


class Job:
    """One command whose output is replaced: `outputs` are the paths compared against the
    references; `prepare(prior)` puts the prior state in place; `kill_args(prior)` is the
    command killed, `next_args()` the one run after it."""

    name = ""

    def __init__(self, runner, work, scenario, quick):
        self.runner = runner
        self.work = Path(work) / self.name
        self.work.mkdir(parents=True, exist_ok=True)
        self.scenario = scenario
        self.quick = quick
        self.refs = {}  # state -> {output: snapshot}
        self.copies = {}  # state -> {output: path of a saved copy}
        self.duration = {}  # prior -> seconds of an uninterrupted kill command
        self.renames = {}  # prior -> rename calls of an uninterrupted kill command
        self.rename_log = {}

    def priors(self):
        # Quick mode: only the replacing write of an old result by a new one.
        return ["old"] if self.quick else ["absent", "old", "new"]

    def outputs(self):
        raise NotImplementedError

    def current(self):
        return {name: snapshot(path) for name, path in self.outputs().items()}

    def prepare(self, prior):
        for name, path in self.outputs().items():
            copy_result(self.copies[prior][name] if prior != "absent" else None, path)

    def save_reference(self, state):
        keep = self.work / "references" / state
        self.copies[state] = {}
        for name, path in self.outputs().items():
            copy = keep / name
            copy_result(path if Path(path).exists() else None, copy)
            self.copies[state][name] = copy if Path(path).exists() else None
        self.refs[state] = self.current()

    def classify(self, now, prefer="old"):
        """For each output, which reference state it equals ('absent', 'old', 'new'), or None;
        `prefer` when it equals both."""
        labels = {}
        for name, snap in now.items():
            label = None
            if snap is None:
                label = "absent"
            else:
                for state in (prefer, "new" if prefer == "old" else "old"):
                    if state in self.refs and self.refs[state].get(name) == snap:
                        label = state
                        break
            labels[name] = label
        return labels


class GraphJob(Job):
    name = "graph"
    NEW = ["--set", "graph.threshold=0.5"]

    def setup(self):
        self.cache = self.work / "cache"
        self.bundle = None
        for state, extra in (("old", []), ("new", self.NEW)):
            shutil.rmtree(self.cache, ignore_errors=True)
            rc, _, err, _ = self.runner.run(["graph", self.scenario, "--cache", self.cache, "--json"] + extra, self.work)
            if rc != 0:
                raise RuntimeError(f"graph reference ({state}) failed: {err}")
            bundles = sorted((self.cache / "graphs").iterdir())
            self.bundle = bundles[0]
            self.save_reference(state)

    def outputs(self):
        return {"bundle": self.bundle}

    def kill_args(self, prior, resume=False):
        # A cache that already holds the new graph is replaced only when asked (--no-cache).
        return ["graph", self.scenario, "--cache", self.cache, "--json"] + self.NEW + (["--no-cache"] if prior == "new" else [])

    def next_args(self, resume=False):
        return ["graph", self.scenario, "--cache", self.cache, "--json"] + self.NEW

    def check_next(self, after_kill, err):
        problems = []
        if after_kill.get("bundle") == "new" and "graph: reused" not in err:
            problems.append("the graph found whole after the kill was not reused: " + last_line(err))
        if "damaged" in err:
            problems.append("the next run found a damaged cache: " + last_line(err))
        return problems


class TrainJob(Job):
    name = "train"

    def budgets(self):
        if self.quick:
            return ["--set", "behaviors.approach.learner.budget=100000",
                    "--set", "behaviors.approach.learner.checkpoint_every=40000",
                    "--set", "behaviors.hit.learner.budget=100000",
                    "--set", "behaviors.hit.learner.checkpoint_every=40000"]
        return ["--set", "behaviors.approach.learner.budget=300000",
                "--set", "behaviors.approach.learner.checkpoint_every=100000",
                "--set", "behaviors.hit.learner.budget=400000",
                "--set", "behaviors.hit.learner.checkpoint_every=100000"]

    def settings(self, state):
        seed = "1" if state == "new" else "2"
        return self.budgets() + ["--set", f"behaviors.approach.learner.seed={seed}",
                                 "--set", f"behaviors.hit.learner.seed={seed}"]

    def setup(self):
        self.cache = self.work / "cache"
        self.out = self.work / "policy"
        for state in ("old", "new"):
            copy_result(None, self.out)
            rc, _, err, seconds = self.runner.run(self.args(state), self.work)
            if rc != 0:
                raise RuntimeError(f"train reference ({state}) failed: {err}")
            self.save_reference(state)
        # The reference is a good policy as mgrl reads it: eval takes it.
        rc, _, err, _ = self.runner.run(["eval", self.scenario, "--cache", self.cache, "--policy", self.out,
                                         "--trials", "5", "--json"] + self.settings("new"), self.work)
        if rc != 0:
            raise RuntimeError(f"eval of the train reference failed: {err}")

    def args(self, state, resume=False):
        return (["train", self.scenario, "--cache", self.cache, "--out", self.out, "--json"] + self.settings(state) +
                (["--resume"] if resume else []))

    def outputs(self):
        return {"policy": self.out}

    def prepare(self, prior):
        super().prepare(prior)
        shutil.rmtree(str(self.out) + ".checkpoints", ignore_errors=True)

    def kill_args(self, prior, resume=False):
        return self.args("new", resume)

    def next_args(self, resume=False):
        return self.args("new", resume)

    def check_next(self, after_kill, err, resume=False):
        problems = []
        if "not keeping" in err:
            problems.append("the next run could not read the bundle: " + last_line(err))
        if not resume and re.search(r"^mgrl: resume: .*continuing from", err, re.M):
            problems.append("a run without --resume continued from a checkpoint: " +
                            re.search(r"^mgrl: resume: .*$", err, re.M).group(0))
        return problems


class SimulateJob(Job):
    name = "simulate"

    def __init__(self, runner, work, scenario, quick, policy, settings, events_inside):
        self.events_inside = events_inside
        self.name = "simulate-events-inside" if events_inside else "simulate-events-outside"
        super().__init__(runner, work, scenario, quick)
        self.policy = policy
        self.settings = settings

    def setup(self):
        self.cache = self.work / "cache"
        self.out = self.work / "out"
        self.events = self.out / "hits.jsonl" if self.events_inside else self.work / "events" / "hits.jsonl"
        for state in ("old", "new"):
            copy_result(None, self.out)
            copy_result(None, self.events)
            rc, _, err, _ = self.runner.run(self.args(state), self.work)
            if rc != 0:
                raise RuntimeError(f"simulate reference ({state}) failed: {err}")
            self.save_reference(state)
        for name in self.refs["new"]:
            if self.refs["new"][name] == self.refs["old"][name]:
                print(f"kill_test: note: {self.name}: {name} is the same for the old and the new run", flush=True)

    def args(self, state):
        seed, avatars = ("2", "3") if state == "new" else ("1", "2")
        seconds = "6" if self.quick else "10"
        return (["simulate", self.scenario, "--cache", self.cache, "--policy", self.policy, "--json",
                 "--seed", seed, "--avatars", avatars, "--seconds", seconds, "--threads", "1",
                 "--bvh-out", self.out, "--events-out", self.events] + self.settings)

    def outputs(self):
        outputs = {"bvh_out": self.out}
        if not self.events_inside:
            outputs["events_out"] = self.events
        return outputs

    def kill_args(self, prior, resume=False):
        return self.args("new")

    def next_args(self, resume=False):
        return self.args("new")

    def check_next(self, after_kill, err, resume=False):
        return []


def last_line(text):
    lines = [line for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else "(nothing on stderr)"


class KillTest:
    def __init__(self, args):
        self.args = args
        self.random = random.Random(args.seed)
        self.findings = []
        self.kills = Counter()  # (command, kill point) -> count
        self.not_killed = Counter()
        self.outcomes = Counter()  # (command, outcome) -> count
        self.runs = 0
        self.follow_ups = Counter()

    def finding(self, job, where, text):
        line = f"{job.name}: {where}: {text}"
        self.findings.append(line)
        print("FINDING", line, flush=True)

    def count_renames(self, job, prior):
        job.prepare(prior)
        log = job.work / f"renames-{prior}.log"
        if log.exists():
            log.unlink()
        rc, _, err, seconds = self.runner.run(job.kill_args(prior), job.work, count_log=log)
        if rc != 0:
            raise RuntimeError(f"{job.name} with the shim counting renames failed: {err}")
        calls = log.read_text().splitlines() if log.exists() else []
        job.renames[prior] = len(calls)
        job.rename_log[prior] = calls
        job.duration[prior] = seconds
        self.check_result(job, prior, "uninterrupted", job.current(), allow={"new"})
        self.check_leftovers(job, "uninterrupted run")

    def check_result(self, job, prior, where, now, allow):
        labels = job.classify(now, prefer="old" if prior == "old" else "new")
        for name, label in labels.items():
            if label is None:
                self.finding(job, where, f"{name} is neither the previous nor the new complete result "
                                         f"(prior {prior}): {describe(now[name])}")
            elif label not in allow:
                self.finding(job, where, f"{name} is {label}, expected one of {sorted(allow)}")
        return labels

    def check_leftovers(self, job, where):
        left = leftovers(job.work)
        left = [l for l in left if not l.startswith("references")]
        for item in left:
            self.finding(job, where, f"left behind: {item}")

    def round(self, job, prior, point, delay=None, chain=1, resume_next=False):
        """One kill round: put `prior` in place, kill the command (at rename `point` or after
        `delay` seconds), check, maybe kill again (chain), then run it to the end and check."""
        job.prepare(prior)
        state = prior
        where = f"prior {prior}, kill at {point}"
        for link in range(chain):
            resume = link > 0 and job.name == "train" and self.random.random() < 0.7
            args = job.kill_args(prior, resume)
            if link == 0 and point.startswith("rename"):
                n, phase = point.split()[1].split("/")
                rc, out, err, seconds = self.runner.run(args, job.work, kill_rename=(int(n), phase))
            elif link == 0 and point.startswith("unlink"):
                rc, out, err, seconds = self.runner.run(args, job.work, kill_unlink=point.split()[1])
            else:
                d = delay if link == 0 else self.random.uniform(0.05, 1.1) * job.duration.get(prior, 2.0)
                rc, out, err, seconds = self.runner.run(args, job.work, kill_delay=d)
            self.runs += 1
            kind = point if link == 0 else "random (chained" + (", --resume)" if resume else ")")
            label = (kind.split()[0] + " " + kind.split()[1].split("/")[1] if kind.startswith("rename") else
                     kind if kind.startswith("unlink") else kind.split()[0])
            if rc == -signal.SIGKILL:
                self.kills[(job.name, label)] += 1
            elif rc == 0:
                self.not_killed[(job.name, label)] += 1
                if link == 0 and point == "random":
                    # The run ended before the kill: its duration, measured again (the
                    # machine's load changes), scales the next delays.
                    job.duration[prior] = seconds
            else:
                # A clear refusal is allowed, but nothing here should refuse: say it.
                self.finding(job, where, f"the killed command failed on its own (exit {rc}): {last_line(err)}")
            allow = {state, "new"}
            labels = self.check_result(job, prior, where + (f" (link {link + 1})" if link else ""), job.current(), allow)
            for name, label in labels.items():
                self.outcomes[(job.name, f"{name}={label}")] += 1
            # The next link starts from what this one left.
            states = set(labels.values())
            state = states.pop() if len(states) == 1 and None not in states else state

        after_kill = job.classify(job.current())
        rc, out, err, seconds = self.runner.run(job.next_args(resume_next), job.work)
        self.runs += 1
        self.follow_ups[(job.name, "--resume" if resume_next else "plain")] += 1
        if rc != 0:
            self.finding(job, where, f"the next run failed (exit {rc}): {last_line(err)}")
            return
        for name, snap in job.current().items():
            if snap != job.refs["new"][name]:
                self.finding(job, where, f"after the next run{' (--resume)' if resume_next else ''}, {name} differs "
                                         f"from an uninterrupted run's: {describe_difference(snap, job.refs['new'][name])}")
        kwargs = {"resume": resume_next} if job.name == "train" else {}
        for problem in job.check_next(after_kill, err, **kwargs):
            self.finding(job, where, problem)
        self.check_leftovers(job, where + ", after the next run")

    def main(self):
        args = self.args
        data = os.environ.get("MGRL_DATA")  # else mgrl's own default, ../shared/mocap
        scenario = str(Path(args.scenario).resolve())
        keep = args.keep
        work = Path(tempfile.mkdtemp(prefix="mgrl-kill-", dir=args.tmp))
        start = time.monotonic()
        try:
            shim = work / "rename_kill.so"
            (work / "rename_kill.c").write_text(SHIM_C)
            subprocess.run([args.cc, "-shared", "-fPIC", "-O1", "-o", str(shim), str(work / "rename_kill.c"), "-ldl"],
                           check=True)
            self.runner = Runner(args.mgrl, str(shim), data, args.verbose)

            print(f"kill_test: seed {args.seed}, {'quick' if args.quick else 'full'} mode, work in {work}", flush=True)
            graph = GraphJob(self.runner, work, scenario, args.quick)
            train = TrainJob(self.runner, work, scenario, args.quick)
            t0 = time.monotonic()
            graph.setup()
            train.setup()
            policy = train.copies["new"]["policy"]
            sims = [SimulateJob(self.runner, work, scenario, args.quick, policy, train.settings("new"), inside)
                    for inside in ((False,) if args.quick else (True, False))]
            for sim in sims:
                sim.setup()
            jobs = [graph, train] + sims
            for job in jobs:
                for prior in job.priors():
                    self.count_renames(job, prior)
            print(f"kill_test: references and rename counts in {time.monotonic() - t0:.1f} s", flush=True)
            for job in jobs:
                print(f"  {job.name:24} renames per run by prior state: " +
                      ", ".join(f"{p} {job.renames[p]} ({job.duration[p]:.1f} s)" for p in job.priors()), flush=True)

            plan = self.plan(jobs)
            target = args.runs
            print(f"kill_test: {len(plan)} kill rounds at renames and probes, then " +
                  ("one random kill per job" if args.quick else f"random kills until {target} SIGKILLs in all"),
                  flush=True)
            for i, (job, prior, point, delay, chain, resume_next) in enumerate(self.rounds(jobs, plan, target)):
                if args.verbose or (i + 1) % 10 == 0:
                    print(f"  [{time.monotonic() - start:6.0f} s] round {i + 1}, {sum(self.kills.values())} kills: "
                          f"{job.name}, prior {prior}, {point}{f' {delay:.2f} s' if delay is not None else ''}" +
                          (f", {chain} kills" if chain > 1 else "") + (", then --resume" if resume_next else ""),
                          flush=True)
                self.round(job, prior, point, delay, chain, resume_next)
            self.check_kills_landed(jobs)
        except (RuntimeError, subprocess.CalledProcessError, OSError) as e:
            print(f"kill_test: setup error: {e}", file=sys.stderr)
            return 2
        finally:
            if keep or self.findings:
                print(f"kill_test: work folder kept: {work}")
            else:
                shutil.rmtree(work, ignore_errors=True)
        self.summary(time.monotonic() - start)
        return 1 if self.findings else 0

    def check_kills_landed(self, jobs):
        """A run whose kills all came after the command ended tested nothing: every command
        must have been SIGKILLed at least once, and every kill at a rename or unlink (the
        shim stops the process inside the call, so it cannot come late) must have landed."""
        for job in jobs:
            landed = sum(v for (c, _), v in self.kills.items() if c == job.name)
            if landed == 0:
                self.finding(job, "all rounds", "no SIGKILL landed: every planned kill came after the run ended, "
                                                "so nothing was tested")
            missed = sorted(p for (c, p), v in self.not_killed.items() if c == job.name and v and p != "random")
            if missed:
                self.finding(job, "all rounds", f"the kills at {', '.join(missed)} did not land: the shim never "
                                                f"stopped the command inside the call")

    def plan(self, jobs):
        """Every rename of every job and prior state, before and after the call (a sample of
        them in quick mode), then random-time kills up to --runs."""
        rename_rounds = []
        for job in jobs:
            for prior in job.priors():
                for n in range(1, job.renames[prior] + 1):
                    for phase in ("before", "after"):
                        rename_rounds.append((job, prior, f"rename {n}/{phase}", None))
        # Train's writability probe (`.<out>.probe-PID`), made before training and removed
        # at once: a kill between the two.
        for job in jobs:
            if job.name == "train":
                for prior in job.priors():
                    rename_rounds.append((job, prior, "unlink .probe-", None))
        if self.args.quick:
            # One kill per command at a rename that replaces, and one random kill each.
            picked = []
            for job in jobs:
                options = [r for r in rename_rounds if r[0] is job and r[1] == "old"]
                picked.append(self.random.choice(options))
            rename_rounds = picked
        return [(job, prior, point, delay, 1, job.name == "train" and self.random.random() < 0.5)
                for job, prior, point, delay in rename_rounds]

    def rounds(self, jobs, plan, target):
        """The planned rounds, then random-time kills until `target` SIGKILLs in all (quick
        mode: one random round per job), drawn over each job's latest measured duration."""
        yield from plan
        weights = {"graph": 1, "train": 3, "simulate-events-inside": 1, "simulate-events-outside": 1}
        cycle = jobs if self.args.quick else [job for job in jobs for _ in range(weights.get(job.name, 1))]
        for i in range(len(jobs) if self.args.quick else 10 * max(target, 1)):
            if not self.args.quick and sum(self.kills.values()) >= target:
                return
            job = cycle[i % len(cycle)]
            prior = self.random.choice(job.priors())
            delay = self.random.uniform(0.02, 1.0) * job.duration[prior]
            chain = 2 if job.name == "train" and not self.args.quick and self.random.random() < 0.3 else 1
            resume_next = job.name == "train" and self.random.random() < 0.5
            yield (job, prior, "random", delay, chain, resume_next)

    def summary(self, seconds):
        print()
        print(f"kill_test summary ({seconds:.0f} s, seed {self.args.seed}): {self.runs} mgrl runs, "
              f"{sum(self.kills.values())} SIGKILLs, {sum(self.not_killed.values())} planned kills that came "
              f"after the run ended")
        commands = sorted({c for c, _ in self.kills} | {c for c, _ in self.not_killed})
        for command in commands:
            points = sorted({p for c, p in self.kills if c == command} | {p for c, p in self.not_killed if c == command})
            print(f"  {command}: {sum(v for (c, _), v in self.kills.items() if c == command)} kills")
            for point in points:
                late = self.not_killed[(command, point)]
                print(f"    {point:28} {self.kills[(command, point)]:4} killed" + (f", {late} finished first" if late else ""))
            outcomes = ", ".join(f"{o} {v}" for (c, o), v in sorted(self.outcomes.items()) if c == command)
            print(f"    left after the kills: {outcomes}")
            follow = ", ".join(f"{k} {v}" for (c, k), v in sorted(self.follow_ups.items()) if c == command)
            print(f"    next runs: {follow}")
        if self.findings:
            print(f"{len(self.findings)} findings:")
            for f in self.findings:
                print("  " + f)
        else:
            print("no findings: every output was the old or the new complete result, every next run ended with "
                  "the uninterrupted run's result, and nothing was left behind")


def describe(snap):
    if snap is None:
        return "absent"
    if snap[0] == "file":
        return "a file of other content"
    names = [name for name, _ in snap[1]]
    return "a folder holding " + (", ".join(names) if names else "nothing")


def describe_difference(a, b):
    if a is None or b is None:
        return f"{describe(a)} against {describe(b)}"
    if a[0] != "dir" or b[0] != "dir":
        return "other bytes"
    da, db = dict(a[1]), dict(b[1])
    diff = sorted(n for n in set(da) | set(db) if da.get(n) != db.get(n))
    return "differs in " + ", ".join(diff)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mgrl", help="the mgrl binary (build/app/mgrl)")
    parser.add_argument("--runs", type=int, default=220,
                        help="SIGKILLs in all, at least: every rename first, then random kills (default 220)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the kill moments (default 1)")
    parser.add_argument("--quick", action="store_true", help="one kill at a rename and one random kill per job")
    parser.add_argument("--scenario", default=str(Path(__file__).resolve().parents[1] / "scenarios" / "boxing.yaml"))
    parser.add_argument("--cc", default=os.environ.get("CC", "cc"), help="C compiler for the shim (default: $CC or cc)")
    parser.add_argument("--tmp", default=None, help="where the work folder goes (default: the system's)")
    parser.add_argument("--keep", action="store_true", help="keep the work folder")
    parser.add_argument("-v", "--verbose", action="store_true")
    sys.exit(KillTest(parser.parse_args()).main())


if __name__ == "__main__":
    main()
