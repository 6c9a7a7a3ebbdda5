"""MotionGraphEnv and MotionGraphVectorEnv against Gymnasium's contract (the rules of
gym_rules.py: check_env's and the vector API's) on boxing's approach and hit, intercept's
moving target and dodge; and, with a stand-in Gymnasium on the path, as its subclasses.
Run by ctest (python_tests)."""
import os
import subprocess
import sys
import unittest
from pathlib import Path

import numpy as np

import gym_rules
import mgrl
from mgrl import env as mgrl_env
from test_problem import BOXING, CACHE, SOURCE

HERE = Path(__file__).resolve().parent
CASES = [("boxing.yaml", "approach"), ("boxing.yaml", "hit"), ("intercept.yaml", "approach"), ("dodge.yaml", "dodge")]


def edge_starts(env):
    """reset's options for a drawn start, then targets just inside the grid's outer ring in
    six directions (at the middle of its heights), and one beyond it: episodes that leave
    the grid soon, so that terminal observations are among those checked (dodge's opponent
    comes closer, and leaves the grid only when it starts outside)."""
    axes, bounds = env.grid_axes, env.grid_bounds
    reach = bounds[axes.index("distance"), 1]
    height = float(bounds[axes.index("height")].mean()) if "height" in axes else 0.0
    return ([None] + [{"target": [0.97 * reach * np.sin(t), height, 0.97 * reach * np.cos(t)]}
                      for t in np.linspace(0, 2 * np.pi, 6, endpoint=False)]
            + [{"target": [0.3, height, 1.3 * reach]}])


class ConformanceTest(unittest.TestCase):
    sessions = {}

    @classmethod
    def session(cls, scenario):
        if scenario not in cls.sessions:
            path = BOXING if scenario == "boxing.yaml" else SOURCE / "scenarios" / scenario
            cls.sessions[scenario] = mgrl.Session(path, cache=CACHE)
        return cls.sessions[scenario]

    def test_the_environment_keeps_every_rule(self):
        for scenario, behavior in CASES:
            with self.subTest(scenario=scenario, behavior=behavior):
                env = mgrl.MotionGraphEnv(self.session(scenario), behavior, max_seconds=6.0, render_mode="rgb_array",
                                          render_size=48)
                terminated = gym_rules.check_env(env, seed=11, episodes=16, starts=edge_starts(env))
                # Terminal observations were among those checked to lie in the space.
                self.assertGreater(terminated, 0)

    def test_the_vector_environment_keeps_every_rule(self):
        for scenario, behavior in CASES:
            with self.subTest(scenario=scenario, behavior=behavior):
                session = self.session(scenario)
                vec = mgrl.MotionGraphVectorEnv(session, behavior, 6, max_seconds=3.0)
                ended = gym_rules.check_vector_env(
                    vec, mgrl_env.batch_space, lambda: mgrl.MotionGraphEnv(session, behavior, max_seconds=3.0))
                self.assertGreater(ended, 3)

    def test_terminal_observations_lie_beyond_the_grid_inside_the_space(self):
        # The space is not the grid: a terminated episode's target has left the grid, and
        # grid_bounds says where the grid ends.
        env = mgrl.MotionGraphEnv(self.session("boxing.yaml"), "approach")
        radius = env.grid_bounds[1, 1]
        self.assertEqual(radius, 2.0)  # approach's polar2d grid
        rng = np.random.default_rng(4)
        beyond = 0
        for episode in range(100):
            obs, info = env.reset(seed=episode)
            terminated = truncated = False
            while not (terminated or truncated):
                obs, _, terminated, truncated, info = env.step(gym_rules.legal(info, rng))
            if terminated:
                self.assertGreater(obs["coordinates"][1], radius)
                self.assertTrue(env.observation_space.contains(obs))
                beyond += 1
        self.assertGreater(beyond, 10)
        # A wrapping angle: the whole turn, as atan2 gives it; distances from 0.
        np.testing.assert_allclose(env.observation_space["coordinates"].low, [-np.pi, 0], rtol=1e-6)
        self.assertEqual(env.observation_space["coordinates"].high[1], np.inf)

    def test_an_index_past_the_out_actions_wraps_or_is_refused(self):
        session = self.session("boxing.yaml")
        begin = session.graph["state_action_begin"]
        degree = np.diff(begin)
        state = int(np.argmin(degree))
        n = int(degree[state])
        self.assertLess(n, mgrl.MotionGraphEnv(session, "hit").action_space.n)
        wrapped, direct = mgrl.MotionGraphEnv(session, "hit"), mgrl.MotionGraphEnv(session, "hit")
        start = {"state": state, "target": [0.2, 1.2, 0.6]}
        wrapped.reset(seed=2, options=start)
        direct.reset(seed=2, options=start)
        a, b = wrapped.step(n + 1), direct.step(1 % n)
        self.assertTrue(gym_rules.equal(a, b))
        strict = mgrl.MotionGraphEnv(session, "hit", illegal_actions="raise")
        strict.reset(seed=2, options=start)
        with self.assertRaisesRegex(mgrl.Error, rf"action: expected an index into state {state}'s {n} out-actions"):
            strict.step(n)
        with self.assertRaisesRegex(mgrl.Error, r"action: expected an integer in \[0, \d+\), found 1.5"):
            wrapped.step(1.5)
        with self.assertRaisesRegex(mgrl.Error, r"illegal_actions: expected 'wrap' or 'raise', found 'skip'"):
            mgrl.MotionGraphEnv(session, "hit", illegal_actions="skip")
        vec = mgrl.MotionGraphVectorEnv(session, "hit", 2)
        vec.reset(options=start)
        _, reward, terminated, truncated, _ = vec.step(np.array([n + 1, 1 % n]))
        self.assertEqual((reward[0], terminated[0], truncated[0]), (reward[1], terminated[1], truncated[1]))

    def test_the_errors_class_is_mgrl_error(self):
        self.assertEqual(mgrl.Error.__module__, "mgrl")
        self.assertEqual(repr(mgrl.Error), "<class 'mgrl.Error'>")
        self.assertIn("says where", mgrl.Error.__doc__)


class WithGymnasiumTest(unittest.TestCase):
    def test_with_gymnasium_importable_the_classes_are_its_subclasses_and_keep_its_rules(self):
        # Gymnasium is not in Debian 12: a stand-in with its names (tests/python/standin)
        # goes first on the path of a fresh interpreter.
        if mgrl_env._gym is not None and "standin" not in str(Path(mgrl_env._gym.__file__)):
            self.skipTest("Gymnasium itself is installed; ConformanceTest ran against it")
        script = """
import gymnasium, gymnasium.spaces, gymnasium.vector, gymnasium.vector.utils
import mgrl, gym_rules
from test_gymnasium import edge_starts
from test_problem import BOXING, CACHE
s = mgrl.Session(BOXING, cache=CACHE)
env = mgrl.MotionGraphEnv(s, "approach", max_seconds=4.0)
vec = mgrl.MotionGraphVectorEnv(s, "approach", 4, max_seconds=3.0)
assert isinstance(env, gymnasium.Env), type(env).__mro__
assert isinstance(vec, gymnasium.vector.VectorEnv), type(vec).__mro__
assert type(env.action_space) is gymnasium.spaces.Discrete, type(env.action_space)
assert type(env.observation_space) is gymnasium.spaces.Dict
assert type(vec.action_space) is gymnasium.spaces.MultiDiscrete, type(vec.action_space)
assert vec.metadata["autoreset_mode"] is gymnasium.vector.AutoresetMode.SAME_STEP
assert gym_rules.check_env(env, seed=3, episodes=7, starts=edge_starts(env)) > 0
assert gym_rules.check_vector_env(vec, gymnasium.vector.utils.batch_space,
                                  lambda: mgrl.MotionGraphEnv(s, "approach", max_seconds=3.0)) > 0
print("standin ok")
"""
        path = os.pathsep.join([str(HERE / "standin"), str(HERE), os.environ.get("PYTHONPATH", "")])
        result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600,
                                env={**os.environ, "PYTHONPATH": path})
        self.assertEqual(result.returncode, 0, result.stderr[-3000:])
        self.assertIn("standin ok", result.stdout)


if __name__ == "__main__":
    unittest.main()
