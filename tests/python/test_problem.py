"""The tabulated problem from Python: a value iteration written in NumPy on
s.problem(...) reproduces mgrl's C++ value iteration; errors cross as mgrl.Error.
Run by ctest (python_tests) with PYTHONPATH=build-python/python."""
import os
import pathlib
import tempfile
import unittest

import numpy as np

import mgrl

SOURCE = pathlib.Path(os.environ.get("MGRL_SOURCE", pathlib.Path(__file__).resolve().parents[2]))
BOXING = SOURCE / "scenarios" / "boxing.yaml"
CACHE = tempfile.mkdtemp(prefix="mgrl-python-test-")


# Sweeps compared on the larger problems (test_slow_*).
SWEEPS = 15


def numpy_value_iteration(p, tolerance=1e-6, sweeps=2000):
    """The docstring's backup, Jacobi sweeps until the largest change is below tolerance."""
    indptr, _ = p.out_actions
    q = np.zeros(p.rewards.shape, dtype=np.float64)
    inside = p.corners >= 0
    corners = np.where(inside, p.corners, 0)
    weights = np.where(inside, p.weights, 0).astype(np.float64)
    states = len(indptr) - 1
    for _ in range(sweeps):
        # future[s, c]: max over the out-actions a' of s of the interpolated value at the
        # cell whose corners are c. The max is of the interpolated row (as the C++ code does),
        # so it is taken per (a, v) below, state by state.
        new = np.empty_like(q)
        for s in range(states):
            acts = np.arange(indptr[s], indptr[s + 1])
            into = np.nonzero(p.next_state == s)[0]  # the actions that end in s
            if len(into) == 0:
                continue
            if len(acts) == 0:
                new[into] = p.rewards[into]
                continue
            rows = q[acts]  # (n, V)
            # interpolated[a, v, j] = sum_k W[a, v, k] * Q[a'_j, C[a, v, k]]
            gathered = rows[:, corners[into]]  # (n, |into|, V, K)
            interpolated = np.einsum("jivk,ivk->ivj", gathered, weights[into])
            best = interpolated.max(axis=2)
            best = np.where(inside[into].any(axis=2), best, 0.0)
            new[into] = p.rewards[into] + p.discount[into, None] * best
        change = np.abs(new - q).max()
        q = new
        if change < tolerance:
            break
    return q


class ProblemTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.session = mgrl.Session(BOXING, cache=CACHE)

    def test_arrays_have_the_documented_shapes(self):
        p = self.session.problem("approach")
        A, V = p.rewards.shape
        K = 2 ** p.dimension
        self.assertEqual(p.corners.shape, (A, V, K))
        self.assertEqual(p.weights.shape, (A, V, K))
        self.assertEqual(p.discount.shape, (A,))
        self.assertEqual(p.next_state.shape, (A,))
        indptr, indices = p.out_actions
        self.assertEqual(indptr.shape, (p.states + 1,))
        self.assertEqual(indptr[-1], A)
        self.assertEqual(indices.shape, (A,))
        self.assertEqual(p.vertices.shape, (V, p.dimension))
        # Each vertex sits on its axes' values: the angle varies fastest, the same sectors
        # on every ring, the centre ring (distance 0) included, whose position has no angle.
        angles = p.vertices[:, 0].reshape(-1, 13)  # approach's 13 sectors a ring
        np.testing.assert_array_equal(angles, np.tile(angles[0], (len(angles), 1)))
        self.assertEqual(p.vertices[0, 1], 0.0)
        np.testing.assert_allclose(np.diff(angles[0]), angles[0, 1] - angles[0, 0])
        self.assertEqual(p.rewards.dtype, np.float32)
        self.assertEqual(p.corners.dtype, np.int32)
        inside = p.corners >= 0
        np.testing.assert_allclose(p.weights.sum(axis=2)[inside.all(axis=2)], 1.0, atol=1e-5)
        self.assertTrue(((p.weights == 0) | inside).all())
        self.assertTrue((p.discount > 0).all() and (p.discount < 1).all())

    def test_every_attribute_is_there_and_read_only(self):
        p = self.session.problem("approach")
        A, V = p.rewards.shape
        self.assertEqual(p.behavior, "approach")
        self.assertEqual((p.actions, p.vertex_count), (A, V))
        self.assertEqual(p.states, len(p.out_actions[0]) - 1)
        self.assertGreaterEqual(p.tabulate_seconds, 0)
        self.assertGreaterEqual(p.arrays_seconds, 0)
        for name in ("behavior", "rewards", "corners", "weights", "discount", "next_state", "out_actions",
                     "vertices", "states", "actions", "dimension", "tabulate_seconds", "arrays_seconds",
                     "vertex_count"):
            with self.subTest(name=name):
                getattr(p, name)  # bound (a pybind11 class also refuses to set an unknown name)
                with self.assertRaises(AttributeError):
                    setattr(p, name, 0)
        episodes = mgrl._core.Episodes(self.session, "approach", 2, 10.0, False)
        self.assertEqual(episodes.count, 2)
        self.assertEqual(episodes.dimension, p.dimension)
        self.assertEqual(episodes.max_actions, int(np.diff(p.out_actions[0]).max()))
        self.assertEqual(len(episodes.axes), p.dimension)
        for name in ("count", "max_actions", "dimension", "states", "bounds", "axes", "reach"):
            with self.subTest(name=name):
                getattr(episodes, name)
                with self.assertRaises(AttributeError):
                    setattr(episodes, name, 0)

    def test_numpy_value_iteration_reproduces_the_cpp_one(self):
        p = self.session.problem("approach")
        mine = numpy_value_iteration(p)
        theirs = self.session.train("approach", learner="value_iteration", sets={"tolerance": 1e-6})
        self.assertEqual(theirs.shape, mine.shape)
        self.assertEqual(theirs.dtype, np.float32)
        np.testing.assert_allclose(mine, theirs, atol=1e-4)
        self.assertGreater(np.abs(theirs).max(), 0.01)  # not a table of zeros

    @unittest.skipUnless(os.environ.get("MGRL_PYTHON_SLOW") == "1", "slow (twenty seconds): MGRL_PYTHON_SLOW=1")
    def test_slow_numpy_value_iteration_reproduces_the_cpp_one_on_hit(self):
        # The paper's hit problem: 1,438 actions x 1,920 vertices x 8 corners.
        p = self.session.problem("hit")
        self.assertEqual(p.corners.shape[2], 8)
        # The same number of Jacobi sweeps from zero on both sides (not to convergence, as the
        # approach test above does): every sweep is the formula, and 15 of them reach 15
        # actions ahead, across the whole grid.
        mine = numpy_value_iteration(p, tolerance=0, sweeps=SWEEPS)
        theirs = self.session.train("hit", learner="value_iteration", sets={"tolerance": 1e-9, "max_sweeps": SWEEPS})
        np.testing.assert_allclose(mine, theirs, atol=1e-4)
        self.assertGreater(np.abs(theirs).max(), 0.01)

    @unittest.skipUnless(os.environ.get("MGRL_PYTHON_SLOW") == "1", "slow (ten seconds): MGRL_PYTHON_SLOW=1")
    def test_slow_speed_layers_fit_the_same_formula(self):
        # intercept.yaml's moving target: a polar_velocity grid with 3 speed layers, repeated
        # per turn rate (3 here, not the scenario's 5: the arrays are (A, V, 16) and this
        # test is about the layers, not their number). A backup lands exactly on its layers,
        # so the cell's corners are one layer's and the formula holds as it is; the vertices
        # carry the layer's speed and then the turn rate (rad/s) as their last two columns.
        turns = {f"behaviors.{b}.environment.turns": 3 for b in ("approach", "hit")}
        session = mgrl.Session(SOURCE / "scenarios" / "intercept.yaml", cache=CACHE, sets=turns)
        p = session.problem("approach")
        self.assertEqual(p.vertices.shape, (p.rewards.shape[1], p.dimension + 2))
        self.assertEqual(sorted(set(np.round(p.vertices[:, -2], 6))), [0.0, 0.5, 1.0])
        self.assertEqual(sorted(set(np.round(np.degrees(p.vertices[:, -1]), 6))), [-90.0, 0.0, 90.0])
        mine = numpy_value_iteration(p, tolerance=0, sweeps=SWEEPS)
        theirs = session.train("approach", learner="value_iteration", sets={"tolerance": 1e-9, "max_sweeps": SWEEPS})
        np.testing.assert_allclose(mine, theirs, atol=1e-4)
        self.assertGreater(np.abs(theirs).max(), 0.01)

    def test_graph_arrays_view_the_session_without_copying(self):
        g = self.session.graph
        self.assertEqual(g["action_displacement"].shape[1], 3)
        self.assertFalse(g["action_to"].flags.writeable)
        self.assertFalse(g["action_to"].flags.owndata)
        self.assertEqual(g["action_to"].shape, self.session.problem("approach").next_state.shape)
        # Two reads of the graph are views of the same memory, the session's.
        self.assertTrue(np.shares_memory(g["joint_positions"], self.session.graph["joint_positions"]))
        self.assertEqual(g["joint_positions"].shape[1:], (len(g["joint_names"]), 3))

    def test_errors_cross_as_one_line(self):
        with self.assertRaisesRegex(mgrl.Error, r"behavior: expected one of the scenario's behaviours \(approach, hit\), found 'jab'"):
            self.session.problem("jab")
        with self.assertRaisesRegex(mgrl.Error, r"behaviors\.hit\.reward\.gamma: expected gamma 0\.97 as behaviors\.approach\.reward has"):
            mgrl.Session(BOXING, cache=CACHE, sets={"behaviors.hit.reward.gamma": 0.5})


if __name__ == "__main__":
    unittest.main()
