"""MotionGraphEnv and MotionGraphVectorEnv (issue 41): Gymnasium's API on a behaviour,
stepped in C++; what a step does checked against the graph's own arrays. Run by ctest
(python_tests)."""
import os
import subprocess
import sys
import tempfile
import textwrap
import unittest

import numpy as np

import mgrl
from test_problem import BOXING, CACHE


class EnvTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.session = mgrl.Session(BOXING, cache=CACHE)
        cls.graph = cls.session.graph

    def out_degree(self, state):
        begin = self.graph["state_action_begin"]
        return int(begin[state + 1] - begin[state])

    def test_reset_and_step_follow_gymnasiums_api(self):
        env = mgrl.MotionGraphEnv(self.session, "hit")
        obs, info = env.reset(seed=3)
        self.assertEqual(set(obs), {"state", "target", "coordinates"})
        self.assertEqual(obs["target"].dtype, np.float32)
        self.assertEqual(obs["target"].shape, (3,))
        self.assertEqual(obs["coordinates"].shape, (3,))  # hit's grid: angle, distance, height
        self.assertTrue(env.observation_space.contains(obs))
        self.assertEqual(info["action_mask"].dtype, np.bool_)
        self.assertEqual(info["action_mask"].shape, (env.action_space.n,))
        self.assertEqual(int(info["action_mask"].sum()), self.out_degree(obs["state"]))
        self.assertEqual(env.action_space.n, int(np.diff(self.graph["state_action_begin"]).max()))
        result = env.step(int(np.flatnonzero(info["action_mask"])[-1]))
        self.assertEqual(len(result), 5)
        obs2, reward, terminated, truncated, info2 = result
        self.assertIsInstance(reward, float)
        self.assertIsInstance(terminated, bool)
        self.assertIsInstance(truncated, bool)
        self.assertIn("success", info2)
        # A step's observation is a fresh array: keeping the old one is safe.
        self.assertFalse(np.shares_memory(obs["target"], obs2["target"]))

    def test_a_step_moves_the_target_by_the_actions_displacement(self):
        # A static target stays where it is in the world: in the avatar's new frame it is
        # the old position less the action's ground displacement, turned by its yaw.
        env = mgrl.MotionGraphEnv(self.session, "approach")
        begin = self.graph["state_action_begin"]
        rng = np.random.default_rng(1)
        checked = 0
        obs, info = env.reset(seed=7)
        for _ in range(300):
            choice = int(rng.choice(np.flatnonzero(info["action_mask"])))
            action = int(begin[obs["state"]]) + choice
            dx, dz, dyaw = self.graph["action_displacement"][action]
            x, y, z = obs["target"].astype(np.float64)
            qx, qz = x - dx, z - dz
            c, s = np.cos(dyaw), np.sin(dyaw)
            expected = np.array([c * qx - s * qz, y, s * qx + c * qz])
            new, _, terminated, truncated, info = env.step(choice)
            self.assertEqual(new["state"], self.graph["action_to"][action])
            if not (terminated or truncated):
                np.testing.assert_allclose(new["target"], expected, atol=1e-5)
                checked += 1
                obs = new
            else:
                obs, info = env.reset()
        self.assertGreater(checked, 200)

    def test_episodes_end_where_the_grid_ends_and_after_max_seconds(self):
        env = mgrl.MotionGraphEnv(self.session, "approach", max_seconds=3.0)
        radius = 2.0  # approach's polar2d grid
        rng = np.random.default_rng(2)
        endings = {"terminated": 0, "truncated": 0}
        for episode in range(60):
            obs, info = env.reset(seed=episode)
            self.assertLessEqual(np.hypot(obs["target"][0], obs["target"][2]), radius + 1e-6)
            while True:
                obs, _, terminated, truncated, info = env.step(int(rng.choice(np.flatnonzero(info["action_mask"]))))
                if terminated:
                    endings["terminated"] += 1
                    self.assertGreater(np.hypot(obs["target"][0], obs["target"][2]), radius - 1e-6)
                    break
                if truncated:
                    endings["truncated"] += 1
                    self.assertGreaterEqual(info["seconds"], 3.0)
                    break
                self.assertLess(info["seconds"], 3.0)
        self.assertGreater(endings["terminated"], 0)
        self.assertGreater(endings["truncated"], 0)

    def test_the_same_seed_gives_the_same_episode(self):
        def play(seed):
            env = mgrl.MotionGraphEnv(self.session, "hit")
            obs, info = env.reset(seed=seed)
            trace = [obs["state"]]
            for _ in range(20):
                obs, reward, terminated, truncated, info = env.step(0)
                trace += [obs["state"], reward, *obs["target"]]
                if terminated or truncated:
                    obs, info = env.reset()
            return trace

        self.assertEqual(play(4), play(4))
        self.assertNotEqual(play(4), play(5))

    def test_the_vector_env_steps_like_single_envs(self):
        n = 16
        vec = mgrl.MotionGraphVectorEnv(self.session, "hit", n, max_seconds=2.0)
        singles = [mgrl.MotionGraphEnv(self.session, "hit", max_seconds=2.0) for _ in range(n)]
        obs, info = vec.reset(seed=100)
        self.assertEqual(obs["state"].shape, (n,))
        self.assertEqual(obs["target"].shape, (n, 3))
        self.assertEqual(info["action_mask"].shape, (n, vec.single_action_space.n))
        for i, env in enumerate(singles):
            o, _ = env.reset(seed=100 + i)
            self.assertEqual(o["state"], obs["state"][i])
            np.testing.assert_array_equal(o["target"], obs["target"][i])
        rng = np.random.default_rng(3)
        finals = 0
        for _ in range(80):
            actions = np.array([rng.choice(np.flatnonzero(m)) for m in info["action_mask"]])
            obs, reward, terminated, truncated, info = vec.step(actions)
            for i, env in enumerate(singles):
                o, r, te, tr, _ = env.step(int(actions[i]))
                self.assertEqual((r, te, tr), (reward[i], terminated[i], truncated[i]))
                if te or tr:  # the vector env restarted it at once; so does the single one
                    finals += 1
                    self.assertTrue(info["final"][i])
                    env._episodes.reset(0, None)  # same random stream, no new seed
                    o, _ = env._observation()
                self.assertEqual(o["state"], obs["state"][i])
                np.testing.assert_array_equal(o["target"], obs["target"][i])
        self.assertGreater(finals, 0)

    def test_illegal_actions_are_refused(self):
        env = mgrl.MotionGraphEnv(self.session, "hit")
        obs, info = env.reset(seed=1)
        n = self.out_degree(obs["state"])
        with self.assertRaisesRegex(mgrl.Error, rf"action: expected an index into state {obs['state']}'s {n} "
                                                rf"out-actions \(info\['action_mask'\]\), found {n}"):
            env.step(n)
        with self.assertRaisesRegex(mgrl.Error, r"found -1"):
            env.step(-1)
        vec = mgrl.MotionGraphVectorEnv(self.session, "hit", 4)
        vec.reset(seed=1)
        with self.assertRaisesRegex(mgrl.Error, r"actions: expected an integer array of shape \(4,\), found shape \(3,\)"):
            vec.step(np.zeros(3, dtype=np.int64))
        with self.assertRaisesRegex(mgrl.Error, r"actions: expected integers, found dtype float64"):
            vec.step(np.zeros(4))
        with self.assertRaisesRegex(mgrl.Error, r"actions\[2\]: expected an index into state \d+'s \d+ out-actions"):
            vec.step(np.array([0, 0, 500, 0]))
        with self.assertRaisesRegex(mgrl.Error, r"num_envs: expected a number of environments in \[1, 1000000\], found 0"):
            mgrl.MotionGraphVectorEnv(self.session, "hit", 0)
        with self.assertRaisesRegex(mgrl.Error, r"max_seconds: expected seconds of motion per episode in \(0, 3600\], "
                                                r"found 0"):
            mgrl.MotionGraphEnv(self.session, "hit", max_seconds=0)
        with self.assertRaisesRegex(mgrl.Error, r"render_mode: expected None or 'rgb_array', found 'human'"):
            mgrl.MotionGraphEnv(self.session, "hit", render_mode="human")

    def test_render_draws_the_target_where_it_is(self):
        env = mgrl.MotionGraphEnv(self.session, "approach", render_mode="rgb_array", render_size=100)
        obs, _ = env.reset(seed=9)
        image = env.render()
        self.assertEqual(image.shape, (100, 100, 3))
        self.assertEqual(image.dtype, np.uint8)
        red = np.argwhere((image[:, :, 0] > 200) & (image[:, :, 1] < 80))
        self.assertGreater(len(red), 0)
        row, column = red.mean(axis=0)
        x, _, z = obs["target"]
        scale = 0.45 * 100 / 2.0  # the grid's 2 m reach at 45 % of the picture
        self.assertAlmostEqual(column, 50 - x * scale, delta=1.5)
        self.assertAlmostEqual(row, 50 - z * scale, delta=1.5)
        self.assertIsNone(mgrl.MotionGraphEnv(self.session, "approach").render())


class GymnasiumTest(unittest.TestCase):
    def test_with_gymnasium_importable_the_env_is_a_gymnasium_env(self):
        # Gymnasium is not in Debian 12: a stand-in package with its names shows that the
        # environment subclasses gymnasium.Env and builds gymnasium's spaces when it can.
        fake = tempfile.mkdtemp(prefix="mgrl-fake-gymnasium-")
        os.makedirs(os.path.join(fake, "gymnasium"))
        with open(os.path.join(fake, "gymnasium", "__init__.py"), "w") as f:
            f.write(textwrap.dedent("""
                from . import spaces
                class Env:
                    def reset(self, *, seed=None, options=None):
                        self.seeded = seed
                """))
        with open(os.path.join(fake, "gymnasium", "spaces.py"), "w") as f:
            f.write(textwrap.dedent("""
                class Discrete:
                    def __init__(self, n): self.n = n
                class Box:
                    def __init__(self, low, high, shape, dtype): self.shape = shape
                class Dict:
                    def __init__(self, spaces): self.spaces = spaces
                """))
        script = textwrap.dedent(f"""
            import gymnasium, mgrl
            env = mgrl.MotionGraphEnv({str(BOXING)!r}, "hit", cache={CACHE!r})
            assert isinstance(env, gymnasium.Env)
            assert isinstance(env.action_space, gymnasium.spaces.Discrete)
            assert isinstance(env.observation_space, gymnasium.spaces.Dict)
            obs, info = env.reset(seed=3)
            assert env.seeded == 3
            print("ok", env.action_space.n)
            """)
        path = os.pathsep.join([fake, os.environ.get("PYTHONPATH", "")])
        run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                             env=dict(os.environ, PYTHONPATH=path))
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertTrue(run.stdout.startswith("ok "))


if __name__ == "__main__":
    unittest.main()
