"""MotionGraphEnv and MotionGraphVectorEnv: Gymnasium's API on a behaviour, stepped in
C++; what a step does checked against the graph's own arrays and against the tabulated
problem (Session.problem: the reward, the landing and the success at grid vertices), with
episodes placed by reset's options. Run by ctest (python_tests)."""
import unittest

import numpy as np

import mgrl
from test_problem import BOXING, CACHE, SOURCE


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
        self.assertEqual(info["action_mask"].dtype, np.int8)
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
                    self.assertTrue(info["_final_obs"][i])
                    self.assertEqual(info["final_obs"]["state"][i], o["state"])
                    np.testing.assert_array_equal(info["final_obs"]["target"][i], o["target"])
                    env._episodes.reset(0, None)  # same random stream, no new seed
                    o, _ = env._observation()
                    env._last = o
                self.assertEqual(o["state"], obs["state"][i])
                np.testing.assert_array_equal(o["target"], obs["target"][i])
        self.assertGreater(finals, 0)

    def test_illegal_actions_are_refused(self):
        env = mgrl.MotionGraphEnv(self.session, "hit", illegal_actions="raise")
        obs, info = env.reset(seed=1)
        n = self.out_degree(obs["state"])
        with self.assertRaisesRegex(mgrl.Error, rf"action: expected an index into state {obs['state']}'s {n} "
                                                rf"out-actions \(info\['action_mask'\]\), found {n}"):
            env.step(n)
        with self.assertRaisesRegex(mgrl.Error, r"found -1"):
            env.step(-1)
        vec = mgrl.MotionGraphVectorEnv(self.session, "hit", 4, illegal_actions="raise")
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


def vertex_position(p, v):
    """Vertex v of a polar2d or cylindrical3d grid as a position in the avatar's frame (x,
    y, z, m; +z ahead, +x left, as obs["target"]), from its coordinates (angle, distance
    and, in 3-D, height)."""
    angle, distance = p.vertices[v, 0], p.vertices[v, 1]
    height = p.vertices[v, 2] if p.dimension == 3 else 0.0
    return np.array([distance * np.sin(angle), height, distance * np.cos(angle)])


def grid_coordinates(p):
    """Each vertex's coordinates on the grid's axes, (V, dimension)."""
    return p.vertices[:, :p.dimension].copy()


def same_angle(a, b):
    return np.abs(np.angle(np.exp(1j * (np.asarray(a, dtype=np.float64) - b))))


class EnvAgainstProblemTest(unittest.TestCase):
    """Episodes placed at grid vertices by reset's options, stepped, and compared with the
    tabulated problem built independently of the environment (GridModel: the reward of
    action a from vertex v, where the target lands, p.next_state)."""

    @classmethod
    def setUpClass(cls):
        cls.session = mgrl.Session(BOXING, cache=CACHE)
        cls.problems = {name: cls.session.problem(name) for name in ("approach", "hit")}

    def place(self, env, p, state, v):
        """Resets env at graph state `state` with the target at vertex v; checks that the
        observation is that vertex."""
        obs, info = env.reset(options={"state": int(state), "target": vertex_position(p, v)})
        self.assertEqual(obs["state"], state)
        np.testing.assert_allclose(obs["target"], vertex_position(p, v), atol=1e-6)
        coordinates = obs["coordinates"].astype(np.float64)
        if p.vertices[v, 1] > 0:  # the angle, modulo a turn (none at the avatar itself)
            self.assertLess(same_angle(coordinates[0], p.vertices[v, 0]), 1e-5)
        np.testing.assert_allclose(coordinates[1:], p.vertices[v, 1:p.dimension], atol=1e-5)
        return obs, info

    def landing(self, p, a, v):
        """The coordinates where action a takes the target at vertex v, interpolated from the
        problem's cell corners and weights (exact: multilinear weights of a point reproduce
        its coordinates), or None outside the grid."""
        corners, weights = p.corners[a, v], p.weights[a, v].astype(np.float64)
        if corners[0] < 0:
            return None
        c = grid_coordinates(p)[corners]
        c[:, 0] = c[0, 0] + np.angle(np.exp(1j * (c[:, 0] - c[0, 0])))  # a cell across the angle seam
        return weights @ c

    def pairs(self, p, count, seed):
        """`count` (state, vertex) pairs drawn uniformly, then for each state's best-paid
        vertex among a few: pairs where the reward is not 0 wherever the behaviour pays."""
        indptr, _ = p.out_actions
        rng = np.random.default_rng(seed)
        states = rng.choice(np.flatnonzero(np.diff(indptr) > 0), count, replace=False)
        drawn = [(int(s), int(rng.integers(p.vertex_count))) for s in states]
        # The largest rewards of the table: the hit behaviour pays nothing almost everywhere.
        best = np.argsort(p.rewards, axis=None)[::-1][:count]
        paid = [(int(np.searchsorted(indptr, a, side="right") - 1), int(v))
                for a, v in zip(*np.unravel_index(best, p.rewards.shape))]
        return drawn + paid

    def check_rewards(self, name, seed):
        p = self.problems[name]
        indptr, _ = p.out_actions
        env = mgrl.MotionGraphEnv(self.session, name)
        compared = paid = landed = 0
        for state, v in self.pairs(p, 6, seed):
            n = int(indptr[state + 1] - indptr[state])
            # Up to 4 out-actions, always including the state's best paid from v.
            best = int(np.argmax(p.rewards[indptr[state]:indptr[state + 1], v]))
            for choice in sorted({best, *range(min(n, 3))}):
                a = int(indptr[state]) + choice
                with self.subTest(behavior=name, state=state, vertex=v, action=a):
                    self.place(env, p, state, v)
                    obs, reward, terminated, truncated, info = env.step(choice)
                    # The reward of the action from where the target was when it started.
                    np.testing.assert_allclose(reward, p.rewards[a, v], rtol=1e-5, atol=1e-6)
                    self.assertEqual(obs["state"], p.next_state[a])
                    self.assertFalse(truncated)
                    there = self.landing(p, a, v)
                    # The target leaves the grid exactly where the problem has no landing cell.
                    self.assertEqual(terminated, there is None)
                    if there is not None:
                        got = obs["coordinates"].astype(np.float64)
                        self.assertLess(same_angle(got[0], there[0]), 1e-4)
                        np.testing.assert_allclose(got[1:], there[1:], atol=1e-4)
                        landed += 1
                    if name == "hit":  # hit's success (a landed punch) is what its reward pays for
                        self.assertEqual(info["success"], bool(p.rewards[a, v] > 0))
                    compared += 1
                    paid += p.rewards[a, v] > 1e-3
        self.assertGreater(compared, 25)
        self.assertGreaterEqual(paid, 6)  # at least the best-paid pairs
        self.assertGreater(landed, 5)

    def test_approachs_reward_is_the_tabulated_one_where_the_episode_starts(self):
        self.check_rewards("approach", seed=11)

    def test_hits_reward_is_the_tabulated_one_where_the_episode_starts(self):
        self.check_rewards("hit", seed=12)

    def test_end_on_success_ends_an_episode_where_a_punch_lands(self):
        p = self.problems["hit"]
        indptr, _ = p.out_actions
        # The best-paid (action, vertex) whose target stays in the grid: a punch lands there
        # (hit's contact term pays only for an effective punch within contact_radius).
        for flat in np.argsort(p.rewards, axis=None)[::-1]:
            a, v = (int(i) for i in np.unravel_index(flat, p.rewards.shape))
            if p.corners[a, v, 0] >= 0:
                break
        self.assertGreater(p.rewards[a, v], 0)
        state = int(np.searchsorted(indptr, a, side="right") - 1)
        choice = a - int(indptr[state])
        # And one where nothing lands, also staying in the grid, from the same state.
        missed = [b for b in range(int(indptr[state]), int(indptr[state + 1]))
                  if p.rewards[b, v] == 0 and p.corners[b, v, 0] >= 0]
        self.assertTrue(missed)
        for end_on_success in (False, True):
            with self.subTest(end_on_success=end_on_success):
                env = mgrl.MotionGraphEnv(self.session, "hit", end_on_success=end_on_success)
                self.place(env, p, state, v)
                _, reward, terminated, truncated, info = env.step(choice)
                np.testing.assert_allclose(reward, p.rewards[a, v], rtol=1e-5)
                self.assertTrue(info["success"])
                self.assertEqual(terminated, end_on_success)
                self.assertFalse(truncated)
                self.place(env, p, state, v)
                _, reward, terminated, truncated, info = env.step(missed[0] - int(indptr[state]))
                self.assertEqual(reward, 0.0)
                self.assertFalse(info["success"])
                self.assertFalse(terminated)
        # The vector env ends it too, and restarts that environment at once.
        vec = mgrl.MotionGraphVectorEnv(self.session, "hit", 3, end_on_success=True)
        vec.reset(seed=5, options={"state": state, "target": vertex_position(p, v)})
        _, reward, terminated, _, info = vec.step(np.full(3, choice))
        np.testing.assert_array_equal(terminated, True)
        np.testing.assert_array_equal(info["success"], True)
        np.testing.assert_allclose(reward, p.rewards[a, v], rtol=1e-5)


class ResetOptionsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.session = mgrl.Session(BOXING, cache=CACHE)

    def test_what_options_leave_out_is_drawn_as_without_them(self):
        env = mgrl.MotionGraphEnv(self.session, "hit")
        drawn, _ = env.reset(seed=21)
        obs, _ = env.reset(seed=21, options={"state": 5})
        self.assertEqual(obs["state"], 5)
        np.testing.assert_array_equal(obs["target"], drawn["target"])
        obs, info = env.reset(seed=21, options={"target": (0.1, 1.2, 0.5)})
        self.assertEqual(obs["state"], drawn["state"])
        np.testing.assert_allclose(obs["target"], [0.1, 1.2, 0.5], atol=1e-7)
        self.assertEqual((info["success"], info["seconds"]), (False, 0.0))
        obs, _ = env.reset(options={"state": np.int32(7), "target": np.array([0, 1, 1], dtype=np.float32)})
        self.assertEqual(obs["state"], 7)
        np.testing.assert_array_equal(obs["target"], [0, 1, 1])
        obs, _ = env.reset(seed=21, options={})
        self.assertEqual(obs["state"], drawn["state"])

    def test_a_target_placed_outside_the_grid_ends_the_first_step(self):
        env = mgrl.MotionGraphEnv(self.session, "approach")
        obs, info = env.reset(seed=1, options={"target": [0.0, 0.0, 5.0]})  # approach's grid reaches 2 m
        _, _, terminated, truncated, _ = env.step(0)
        self.assertTrue(terminated)
        self.assertFalse(truncated)

    def test_a_placed_moving_target_keeps_its_drawn_motion(self):
        # intercept.yaml's target moves: placed elsewhere, it moves as the unplaced one drawn
        # from the same seed does, so after an action the two differ by the placement alone,
        # seen from the action's end (turned by its yaw).
        session = mgrl.Session(SOURCE / "scenarios" / "intercept.yaml", cache=CACHE)
        graph = session.graph
        begin = graph["state_action_begin"]
        env = mgrl.MotionGraphEnv(session, "approach")
        moved = 0
        for seed in range(8):
            drawn, _ = env.reset(seed=seed)
            placed = np.array([0.3, 0.0, 1.1])
            obs, _ = env.reset(seed=seed, options={"target": placed})
            self.assertEqual(obs["state"], drawn["state"])
            self.assertAlmostEqual(obs["coordinates"][2], drawn["coordinates"][2], places=6)  # the heading
            action = int(begin[obs["state"]])
            after_placed = env.step(0)[0]["target"].astype(np.float64)
            env.reset(seed=seed)
            after_drawn = env.step(0)[0]["target"].astype(np.float64)
            dx, dz, dyaw = graph["action_displacement"][action]
            c, s = np.cos(dyaw), np.sin(dyaw)
            offset = placed - drawn["target"].astype(np.float64)
            turned = np.array([c * offset[0] - s * offset[2], offset[1], s * offset[0] + c * offset[2]])
            np.testing.assert_allclose(after_placed - after_drawn, turned, atol=1e-5)
            # The drawn target does move (it is not where a static one would be).
            x, y, z = drawn["target"].astype(np.float64)
            static = np.array([c * (x - dx) - s * (z - dz), y, s * (x - dx) + c * (z - dz)])
            moved += np.linalg.norm(after_drawn - static) > 1e-3
        self.assertGreater(moved, 4)

    def test_the_vector_env_places_every_environment_alike(self):
        vec = mgrl.MotionGraphVectorEnv(self.session, "hit", 4)
        obs, _ = vec.reset(seed=3, options={"state": 9, "target": [0.2, 1.0, 0.6]})
        np.testing.assert_array_equal(obs["state"], 9)
        np.testing.assert_allclose(obs["target"], np.tile([0.2, 1.0, 0.6], (4, 1)), atol=1e-7)
        with self.assertRaisesRegex(mgrl.Error, r"options\['state'\]: expected a graph state in \[0, \d+\), found -2"):
            vec.reset(options={"state": -2})

    def test_bad_options_are_refused_saying_where(self):
        env = mgrl.MotionGraphEnv(self.session, "hit")
        before, _ = env.reset(seed=2)
        states = len(self.session.graph["state_action_begin"]) - 1
        target = r"options\['target'\]: expected 3 numbers \(x, y, z in metres, the avatar's frame, as obs\['target'\]\)"
        refusals = [
            ({"stat": 1}, r"options\['stat'\]: expected one of the keys \('state', 'target'\), found 'stat'"),
            ([("state", 1)], r"options: expected None or a dict with keys \('state', 'target'\), found an object of "
                             r"type list"),
            ({"state": states}, rf"options\['state'\]: expected a graph state in \[0, {states}\), found {states}$"),
            ({"state": -1}, rf"options\['state'\]: expected a graph state in \[0, {states}\), found -1$"),
            ({"state": 2 ** 70}, rf"options\['state'\]: expected a graph state in \[0, {states}\), found {2 ** 70}$"),
            ({"state": "3"}, r"options\['state'\]: expected a graph state in \[0, \d+\), found '3' of type str"),
            ({"state": 2.0}, r"options\['state'\]: expected a graph state in \[0, \d+\), found 2.0 of type float"),
            ({"state": True}, r"options\['state'\]: expected a graph state in \[0, \d+\), found True of type bool"),
            ({"target": [0.0, 1.0]}, target + r", found shape \(2,\)"),
            ({"target": [[0.0, 1.0, 0.5]]}, target + r", found shape \(1, 3\)"),
            ({"target": 0.5}, target + r", found an object of type float"),
            ({"target": ["a", "b", "c"]}, target + r", found dtype <U1"),
            ({"target": [np.nan, 1.0, 0.5]}, r"options\['target'\]: expected a finite position \(x, y, z in metres, "
                                             r"the avatar's frame\), found \(nan, 1, 0.5\)"),
            ({"target": [0.0, np.inf, 0.5]}, r"options\['target'\]: expected a finite position .*found \(0, inf, 0.5\)"),
            ({"state": 3, "target": [0.0, 1.0]}, target + r", found shape \(2,\)"),
        ]
        for options, message in refusals:
            with self.subTest(options=options):
                with self.assertRaisesRegex(mgrl.Error, message):
                    env.reset(options=options)
                # A refused reset leaves the episode as it was.
                state, position, _, _ = env._episodes.observe(0)
                self.assertEqual(state, before["state"])
                np.testing.assert_array_equal(position, before["target"])


if __name__ == "__main__":
    unittest.main()
