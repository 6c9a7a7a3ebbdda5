"""mgrl.compare: a learner written in Python beside mgrl's C++ learners, with
mgrl compare's measures, curves and report. Run by ctest (python_tests)."""
import json
import pathlib
import tempfile
import unittest

import numpy as np

import mgrl
from test_problem import BOXING, numpy_value_iteration

SETS = {"behaviors.hit.learner.budget": 300000, "behaviors.approach.learner.budget": 300000}


class SweepLearner:
    """Value iteration in NumPy, a snapshot after each of a few sweeps."""
    name = "numpy_sweeps"

    def train(self, problem, budget, rng, observer):
        sweeps = max(1, len(observer.snapshot_points))
        table = None
        for i in range(sweeps):
            table = numpy_value_iteration(problem, sweeps=(i + 1) * 10).astype(np.float32)
            observer.snapshot(table, (i + 1) * 10 * table.size)
        return table


class Broken:
    name = "broken"

    def train(self, problem, budget, rng, observer):
        raise ValueError("the learner's own mistake")


class CompareTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.session = mgrl.Session(BOXING, cache=tempfile.mkdtemp(prefix="mgrl-python-compare-"), sets=SETS)

    def test_a_python_learner_beside_cpp_ones_with_the_report(self):
        out = pathlib.Path(tempfile.mkdtemp(prefix="mgrl-python-report-")) / "report"
        lines = []
        r = mgrl.compare(self.session, "approach", ["value_iteration", "q_learning", SweepLearner()], seeds=[1, 2],
                         trials=40, snapshots=3, report=out, log=lines.append)
        self.assertEqual(r["learner_names"], ["value_iteration", "q_learning", "numpy_sweeps"])
        # value_iteration has no seed: one run; the others one per seed.
        self.assertEqual([(x["learner"], x["seed"]) for x in r["runs"]],
                         [("value_iteration", None), ("q_learning", 1), ("q_learning", 2), ("numpy_sweeps", 1),
                          ("numpy_sweeps", 2)])
        mine = r["runs"][3]
        self.assertTrue(mine["python"])
        self.assertEqual(len(mine["snapshots"]["points"]), 3)
        # Thirty sweeps of value iteration are close to the reference, not equal to it.
        self.assertGreater(mine["greedy_agreement"], 0.8)
        self.assertLess(mine["value_rmse"], 0.2)
        self.assertEqual(r["runs"][0]["value_rmse"], 0)
        self.assertGreater(mine["success_rate"], 0.8)
        self.assertEqual(len(r["learners"]["numpy_sweeps"]["success_curve"]), 3)
        saved = json.loads((out / "results.json").read_text())
        self.assertEqual(len(saved["runs"]), 5)
        self.assertIn("numpy_sweeps", (out / "index.html").read_text())
        self.assertIn("numpy_sweeps,1,", (out / "results.csv").read_text())
        self.assertIn("numpy_sweeps,1,snapshot,", (out / "curves.csv").read_text())
        self.assertTrue(any("numpy_sweeps" in line and "agreement" in line for line in lines))

    def test_rmse_and_agreement_are_what_numpy_computes_from_the_tables(self):
        # Per graph state and vertex: the table's greedy action among the state's actions,
        # its value less the reference's best (RMSE over them), and whether the reference
        # scores that action within 1e-6 (relative, at least absolute) of its best.
        p = self.session.problem("approach")
        indptr, indices = p.out_actions
        rng = np.random.default_rng(7)
        reference = rng.normal(10.0, 1.0, p.rewards.shape).astype(np.float32)
        # Near-ties at two to four times the tolerance, so that the tolerance decides.
        table = (reference + rng.uniform(-4e-5, 4e-5, reference.shape)).astype(np.float32)
        table[:, ::3] += rng.normal(0.0, 0.5, table[:, ::3].shape).astype(np.float32)
        squares, agree, count = 0.0, 0, 0
        for s in range(len(indptr) - 1):
            actions = indices[indptr[s]:indptr[s + 1]]
            if len(actions) == 0:
                continue
            q = table[actions].astype(np.float64)
            r = reference[actions].astype(np.float64)
            best = np.argmax(q, axis=0)
            ref_best = r.max(axis=0)
            columns = np.arange(q.shape[1])
            squares += float(((q[best, columns] - ref_best) ** 2).sum())
            agree += int((ref_best - r[best, columns] <= 1e-6 * np.maximum(1.0, np.abs(ref_best))).sum())
            count += q.shape[1]
        measured = self.session.compare_tables("approach", table, reference)
        self.assertAlmostEqual(measured["value_rmse"], np.sqrt(squares / count), places=9)
        self.assertEqual(measured["greedy_agreement"], agree / count)
        # The tolerance matters here: neither all nor none of the greedy actions agree.
        self.assertGreater(agree / count, 0.05)
        self.assertLess(agree / count, 0.95)
        self.assertFalse(measured["reference_interpolated"])

    def test_a_learner_that_raises_stops_the_comparison_and_writes_nothing(self):
        out = pathlib.Path(tempfile.mkdtemp(prefix="mgrl-python-report-")) / "report"
        with self.assertRaisesRegex(ValueError, "the learner's own mistake"):
            mgrl.compare(self.session, "approach", ["value_iteration", Broken()], trials=10, snapshots=0, report=out,
                         log=None)
        self.assertEqual(list(out.iterdir()), [])

    def test_mistakes_are_refused_before_training(self):
        with self.assertRaisesRegex(mgrl.Error, r"learners: expected a registered learner \(.*value_iteration.*\), "
                                                r"found 'sarsa'"):
            mgrl.compare(self.session, "approach", ["value_iteration", "sarsa"], log=None)
        with self.assertRaisesRegex(mgrl.Error, "learners: expected each learner once"):
            mgrl.compare(self.session, "approach", ["q_learning", "q_learning"], log=None)
        with self.assertRaisesRegex(mgrl.Error, r"learners: expected a name or an object with train"):
            mgrl.compare(self.session, "approach", [42], log=None)
        with self.assertRaisesRegex(mgrl.Error, "report .*: expected a folder where files can be written"):
            mgrl.compare(self.session, "approach", ["value_iteration"], report="/proc/mgrl-report", log=None)


if __name__ == "__main__":
    unittest.main()
