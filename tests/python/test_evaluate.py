"""Tables from Python played by mgrl: Session.evaluate reports what `mgrl eval`
does, save_policy writes a bundle the command line accepts as it is, NumPy tables of the
wrong shape, dtype or values are refused naming both shapes, and training honours a
progress callback and Ctrl-C. Run by ctest (python_tests)."""
import json
import os
import pathlib
import signal
import subprocess
import sys
import tempfile
import textwrap
import time
import unittest

import numpy as np

import mgrl
from test_problem import BOXING, CACHE, numpy_value_iteration

MGRL = os.environ.get("MGRL_BIN", str(pathlib.Path(__file__).resolve().parents[2] / "build" / "app" / "mgrl"))
# Small budgets, so that the behaviour a test does not give (hit) trains in a second.
SETS = {"behaviors.hit.learner.budget": 300000, "behaviors.approach.learner.budget": 300000}


class PolicyTest(unittest.TestCase):
    """Saved policy bundles in Python: Session(policy=), load_policy, and evaluate, simulate
    and save_policy never training a missing behaviour unless asked."""

    @classmethod
    def setUpClass(cls):
        cls.cache = tempfile.mkdtemp(prefix="mgrl-python-policy-")
        cls.session = mgrl.Session(BOXING, cache=cls.cache, sets=SETS)
        problem = cls.session.problem("approach")
        cls.approach = numpy_value_iteration(problem).astype(np.float32)
        cls.hit = cls.session.train("hit")
        cls.bundle = pathlib.Path(tempfile.mkdtemp(prefix="mgrl-python-policy-")) / "saved"
        cls.session.save_policy(cls.bundle, {"approach": cls.approach, "hit": cls.hit}, learner="numpy_vi")

    def fresh(self, **kwargs):
        """A session with a cache of its own: no trained bundle there."""
        return mgrl.Session(BOXING, cache=tempfile.mkdtemp(prefix="mgrl-python-policy-"), sets=SETS, **kwargs)

    def test_a_missing_table_is_an_error_that_says_how_to_get_one(self):
        s = self.fresh()
        expected = (r"expected a table for behaviour 'hit' \(no trained bundle\), found none to play; pass one in "
                    r"tables \(tables=\{'hit': s.train\('hit'\)\}\), open the session with policy=FOLDER .*, or "
                    r"pass train_missing=True to train it here with q_learning")
        with self.assertRaisesRegex(mgrl.Error, "evaluate: " + expected):
            s.evaluate({"approach": self.approach}, trials=5)
        with self.assertRaisesRegex(mgrl.Error, "simulate: " + expected):
            s.simulate({"approach": self.approach}, seconds=1)
        folder = pathlib.Path(tempfile.mkdtemp(prefix="mgrl-python-policy-")) / "p"
        with self.assertRaisesRegex(mgrl.Error, "save_policy: " + expected):
            s.save_policy(folder, {"approach": self.approach})
        self.assertFalse(folder.exists())
        # Given every table, nothing is missing.
        r = s.evaluate({"approach": self.approach, "hit": self.hit}, trials=5)
        self.assertEqual(r["trials"], 5)

    def test_a_saved_policy_plays_without_training_anything(self):
        s = self.fresh(policy=self.bundle)
        code = textwrap.dedent(f"""
            import sys, mgrl
            s = mgrl.Session({str(BOXING)!r}, cache={tempfile.mkdtemp()!r}, sets={SETS!r}, policy={str(self.bundle)!r})
            r = s.evaluate(trials=40, seed=2)
            print(r["success_rate"])
            """)
        run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertNotIn("training", run.stderr)  # nothing trained: the bundle's tables played
        given = self.session.evaluate({"approach": self.approach, "hit": self.hit}, trials=40, seed=2)
        self.assertEqual(float(run.stdout.split()[-1]), given["success_rate"])
        # The bundle gives what it lacks: its hit beside a table given for approach.
        r = s.evaluate({"approach": self.approach}, trials=40, seed=2)
        self.assertEqual(r["success_rate"], given["success_rate"])
        loaded = mgrl.load_policy(self.bundle, s)
        self.assertEqual(set(loaded), {"approach", "hit"})
        np.testing.assert_array_equal(loaded["approach"], self.approach)
        np.testing.assert_array_equal(loaded["hit"], self.hit)
        self.assertEqual(loaded["hit"].dtype, np.float32)

    def test_a_folder_without_a_bundle_is_refused_saying_so(self):
        missing = pathlib.Path(tempfile.mkdtemp(prefix="mgrl-python-policy-")) / "none"
        with self.assertRaisesRegex(mgrl.Error, r"policy: expected a policy bundle's folder \(with a manifest.json, as "
                                                rf"mgrl train or save_policy writes\), found nothing at {missing}"):
            self.fresh(policy=missing)
        empty = missing.parent
        with self.assertRaisesRegex(mgrl.Error, rf"load_policy: expected .*found a folder without one: {empty}"):
            mgrl.load_policy(empty, self.session)
        # A bundle made on another graph (another threshold) is refused, naming the folder.
        other = mgrl.Session(BOXING, cache=tempfile.mkdtemp(prefix="mgrl-python-policy-"),
                             sets={"graph.threshold": 0.5, **SETS})
        with self.assertRaisesRegex(mgrl.Error, r"load_policy: .*graph"):
            mgrl.load_policy(self.bundle, other)


class EvaluateTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.cache = tempfile.mkdtemp(prefix="mgrl-python-eval-")
        cls.session = mgrl.Session(BOXING, cache=cls.cache, sets=SETS)
        cls.approach = numpy_value_iteration(cls.session.problem("approach")).astype(np.float32)
        # hit's table, trained once here (a small budget): the tests below find it.
        cls.session.evaluate({"approach": cls.approach}, trials=1, train_missing=True)

    def test_a_python_table_saved_gives_the_same_figures_in_mgrl_eval(self):
        mine = self.session.evaluate({"approach": self.approach}, trials=120, seed=3)
        self.assertEqual(mine["trials"], 120)
        self.assertEqual(mine["controller"], "policy")
        # Random actions on the same starts do far worse: the table is really played.
        self.assertGreater(mine["success_rate"], mine["random_baseline"]["success_rate"] + 0.3)
        bundle = pathlib.Path(tempfile.mkdtemp(prefix="mgrl-python-policy-")) / "policy"
        self.session.save_policy(bundle, {"approach": self.approach}, learner="numpy_value_iteration")
        manifest = json.loads((bundle / "manifest.json").read_text())
        self.assertEqual(manifest["provenance"]["python_learners"], {"approach": "numpy_value_iteration"})
        self.assertEqual(manifest["behaviors"]["approach"]["record"]["learner"], "numpy_value_iteration")
        self.assertEqual(set(manifest["behaviors"]), {"approach", "hit"})
        saved = np.load(bundle / "approach.q.npy")
        np.testing.assert_array_equal(saved, self.approach)
        command = [MGRL, "eval", str(BOXING), "--policy", str(bundle), "--json", "--trials", "120", "--seed", "3",
                   "--cache", self.cache]
        for key, value in SETS.items():
            command += ["--set", f"{key}={value}"]
        run = subprocess.run(command, capture_output=True, text=True, check=False)
        self.assertEqual(run.returncode, 0, run.stderr)
        theirs = json.loads(run.stdout)
        for key in ("success_rate", "successes", "mean_return", "mean_time_to_hit_s", "decisions"):
            self.assertEqual(mine[key], theirs[key], key)
        self.assertEqual(mine["random_baseline"], theirs["random_baseline"])
        # simulate takes the same bundle as it is: two avatars spar for two seconds on it.
        simulate = [MGRL, "simulate", str(BOXING), "--policy", str(bundle), "--seconds", "2", "--json", "--cache",
                    self.cache] + command[command.index("--set"):]
        run = subprocess.run(simulate, capture_output=True, text=True, check=False)
        self.assertEqual(run.returncode, 0, run.stderr)
        theirs = json.loads(run.stdout)
        self.assertEqual(theirs["avatars"], 2)
        # Session.simulate plays the same tables in the same world: the same run, hit for hit.
        ours = self.session.simulate({"approach": self.approach}, seconds=2)
        for key in ("avatars", "frames", "hits", "blocked", "decisions", "hits_by_part", "hits_by_avatar", "bodies"):
            self.assertEqual(ours[key], theirs[key], key)
        self.assertNotIn("policy", ours)  # the tables came from Python, not from a bundle folder
        # A session on the graph cached by now is opened without the capture: its first
        # simulate parses it (poses and bodies need it) and plays the same run (hit's table
        # from the bundle saved above).
        warm = mgrl.Session(BOXING, cache=self.cache, sets=SETS, policy=bundle)
        again = warm.simulate({"approach": self.approach}, seconds=2)
        for key in ("avatars", "frames", "hits", "blocked", "decisions", "hits_by_part", "hits_by_avatar", "bodies"):
            self.assertEqual(again[key], theirs[key], key)

    def test_simulate_writes_what_the_command_line_writes_and_refuses_bad_settings(self):
        out = pathlib.Path(tempfile.mkdtemp(prefix="mgrl-python-simulate-"))
        r = self.session.simulate({"approach": self.approach}, avatars=3, seconds=1, seed=2, bvh_out=out / "bvh",
                                  events_out=out / "bvh" / "hits.jsonl")
        self.assertEqual(len(r["bvh_files"]), 3)
        self.assertTrue(all(pathlib.Path(f).is_file() for f in r["bvh_files"]))
        self.assertTrue((out / "bvh" / "manifest.json").is_file())
        self.assertTrue((out / "bvh" / "hits.jsonl").is_file())
        # The same seed gives the same run; the session's own bundle is untouched afterwards.
        again = self.session.simulate({"approach": self.approach}, avatars=3, seconds=1, seed=2)
        self.assertEqual((again["hits"], again["decisions"]), (r["hits"], r["decisions"]))
        # Messages name Python's keywords, not the command line's options.
        with self.assertRaisesRegex(mgrl.Error, r"^avatars: expected a number of avatars in \[1, "):
            self.session.simulate({"approach": self.approach}, avatars=0)
        with self.assertRaisesRegex(mgrl.Error, r"^avatars: expected at most \d+ avatars with poses \(poses, bvh_out or gltf_out\)"):
            self.session.simulate({"approach": self.approach}, avatars=300000, poses=True)
        with self.assertRaisesRegex(mgrl.Error, r"^horizon: expected a search depth in actions in \[1, "):
            self.session.simulate(controller="online_search", horizon=0)
        with self.assertRaisesRegex(mgrl.Error, r"^events_out .*: expected a file name, found a folder"):
            self.session.simulate({"approach": self.approach}, seconds=1, events_out=out)
        self.assertEqual(self.session.simulate(controller="random", seconds=1)["controller"], "random")

    def test_other_controllers_need_no_tables(self):
        r = self.session.evaluate(controller="random", trials=50, seed=2)
        self.assertEqual(r["controller"], "random")
        self.assertNotIn("random_baseline", r)
        r = self.session.evaluate(controller="online_search", horizon=1, trials=10, seed=2)
        self.assertEqual(r["horizon"], 1)

    def test_wrong_tables_are_refused_naming_both_shapes(self):
        q = self.approach
        A, V = q.shape
        cases = [
            (q.astype(np.float64), r"tables\['approach'\]: expected dtype float32, found float64"),
            (q[:, :5], rf"expected shape \({A}, {V}\) \({A} actions of the graph x {V} vertices of approach's polar2d "
                       rf"grid\), found shape \({A}, 5\)"),
            (q.T, rf"expected shape \({A}, {V}\) .* found shape \({V}, {A}\)"),
            (q[0], rf"found shape \({V},\)"),
            ([[0.0]], rf"expected shape \({A}, {V}\) .* found shape \(1, 1\)"),  # a list converts, then is checked
            ([[0.0], [1.0, 2.0]], r"expected a NumPy float32 array of shape .* found an object of type list that "
                                  r"NumPy does not convert to one"),
            (np.where(np.arange(V) == 7, np.inf, q).astype(np.float32), r"expected finite values, found inf at \[0, 7\]"),
        ]
        for table, message in cases:
            with self.subTest(message=message):
                with self.assertRaisesRegex(mgrl.Error, message):
                    self.session.evaluate({"approach": table}, trials=5)
        with self.assertRaisesRegex(mgrl.Error, r"behavior: expected one of the scenario's behaviours \(approach, hit\), found 'jab'"):
            self.session.evaluate({"jab": q}, trials=5)
        with self.assertRaisesRegex(mgrl.Error, r"tables: expected a dict"):
            self.session.evaluate([q], trials=5)
        with self.assertRaisesRegex(mgrl.Error, r"trials: expected a number of trials in \[1, 10000000\], found 0"):
            self.session.evaluate({"approach": q}, trials=0)
        with self.assertRaisesRegex(mgrl.Error, r"controller: expected one of: policy, online_search, random, found 'best'"):
            self.session.evaluate(controller="best")
        # A nested list converts as numpy.asarray(x, float32) would: the same table.
        self.assertEqual(self.session.evaluate({"approach": q.tolist()}, trials=20, seed=4)["success_rate"],
                         self.session.evaluate({"approach": q}, trials=20, seed=4)["success_rate"])
        # A strided view is fine (copied once), the same table as the contiguous one.
        strided = np.asfortranarray(q)
        self.assertEqual(self.session.evaluate({"approach": strided}, trials=20, seed=4)["success_rate"],
                         self.session.evaluate({"approach": q}, trials=20, seed=4)["success_rate"])

    def test_bad_sets_and_learners_are_named_as_python_gives_them(self):
        with self.assertRaisesRegex(mgrl.Error, r"^sets\['behaviors.hit.nope'\] \(= 1\): behaviors.hit.nope: unknown key"):
            mgrl.Session(BOXING, cache=self.cache, sets={"behaviors.hit.nope": 1})
        with self.assertRaisesRegex(mgrl.Error, r"^learner: expected a registered learner \(q_learning, .*\), found 'nope'$"):
            self.session.train("approach", learner="nope")
        with self.assertRaisesRegex(mgrl.Error, r"^sets\['budgt'\]: unknown key \(expected one of: type, tolerance, "):
            self.session.train("approach", learner="value_iteration", sets={"budgt": 3})
        with self.assertRaisesRegex(mgrl.Error, r"^sets\['budget'\]: expected a whole number in \[1, \d+\], found 'x'$"):
            self.session.train("approach", sets={"budget": "x"})

    def test_a_refused_save_leaves_nothing_behind(self):
        folder = pathlib.Path(tempfile.mkdtemp(prefix="mgrl-python-refused-"))
        with self.assertRaisesRegex(mgrl.Error, r"expected dtype float32"):
            self.session.save_policy(folder / "policy", {"approach": self.approach.astype(np.float16)})
        self.assertEqual(list(folder.iterdir()), [])

    def test_train_reports_progress_and_a_raising_callback_stops_it(self):
        seen = []
        q = self.session.train("approach", learner="q_learning", sets={"budget": 2000000}, progress=seen.append)
        self.assertEqual(q.shape, self.approach.shape)
        self.assertTrue(seen)
        self.assertEqual(seen[-1]["behavior"], "approach")
        self.assertTrue(all(a["updates"] <= b["updates"] for a, b in zip(seen, seen[1:])))
        # No placeholders: a residual is None until one is measured, then a non-negative float.
        for d in seen:
            self.assertTrue(d["residual"] is None or (isinstance(d["residual"], float) and d["residual"] >= 0), d)
        self.assertIsInstance(seen[-1]["residual"], float)

        class Enough(Exception):
            pass

        def stop(progress):
            raise Enough(progress["updates"])

        started = time.monotonic()
        with self.assertRaises(Enough):
            self.session.train("approach", learner="q_learning", sets={"budget": 10**10}, progress=stop)
        self.assertLess(time.monotonic() - started, 30)
        with self.assertRaisesRegex(mgrl.Error, r"progress: expected a callable"):
            self.session.train("approach", progress=3)
        with self.assertRaisesRegex(mgrl.Error, r"on_snapshot: expected a callable taking a dict, or None, found an "
                                                r"object of type int"):
            self.session.train("approach", snapshots=2, on_snapshot=3)
        with self.assertRaisesRegex(mgrl.Error, r"snapshots: expected at most 1000, found 1001"):
            self.session.train("approach", snapshots=1001, on_snapshot=print)


class InterruptTest(unittest.TestCase):
    def test_ctrl_c_stops_training_with_keyboard_interrupt(self):
        script = textwrap.dedent(f"""
            import sys, mgrl
            s = mgrl.Session({str(BOXING)!r}, cache={CACHE!r})
            def started(progress):
                if progress["updates"] > 0 and not getattr(started, "said", False):
                    started.said = True
                    print("started", flush=True)
            try:
                s.train("approach", learner="q_learning", sets={{"budget": 10**11}}, progress=started)
            except KeyboardInterrupt as e:
                print("interrupted:", e, flush=True)
                sys.exit(3)
            """)
        child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                 text=True, env=os.environ)
        try:
            self.assertEqual(child.stdout.readline().strip(), "started")
            sent = time.monotonic()
            child.send_signal(signal.SIGINT)
            out, err = child.communicate(timeout=30)
        finally:
            if child.poll() is None:
                child.kill()
        self.assertEqual(child.returncode, 3, err)
        self.assertRegex(out, r"interrupted: interrupted while training approach at \d+ of 100000000000 updates")
        self.assertLess(time.monotonic() - sent, 5)


if __name__ == "__main__":
    unittest.main()
