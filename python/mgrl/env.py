"""One behaviour of a scenario as a reinforcement-learning environment with Gymnasium's
API, stepped in C++ (framework/include/mgrl/session/episodes.hpp says what a step does).

    env = mgrl.MotionGraphEnv("scenarios/boxing.yaml", "hit")
    obs, info = env.reset(seed=1)
    while True:
        a = agent(obs, info["action_mask"])     # an index into the state's out-actions
        obs, reward, terminated, truncated, info = env.step(a)
        if terminated or truncated:
            break

An observation is a dict: "state" (the graph state, int), "target" (the target's
position in the avatar's frame, x, y, z in metres, float32) and "coordinates" (the same
target in the behaviour's grid coordinates, e.g. angle, distance, height; float32). The
action space is Discrete(the most out-actions any state has); only the first
len(out-actions) indices are legal in a state, as info["action_mask"] says, and an
illegal one raises mgrl.Error. The reward is the behaviour's; an episode is terminated
when the target leaves the behaviour's grid (the tabulated problem's edge: no future
value beyond it) or, with end_on_success=True, when its success criterion is met
(info["success"] says when it is met either way); it is truncated after max_seconds of
motion.

reset(seed=..., options=...) can place the episode's start: options is a dict with
"state" (a graph state, an int) and/or "target" (the target's position in the avatar's
frame, x, y, z in metres, as obs["target"]); what it leaves out is drawn as usual (a state
uniformly, a target uniformly inside the grid) from the same random numbers as without
options, and so are the target's other fields (a moving target's speed and heading, an
opponent's facing), at the placed position. A target may be placed outside the grid: the
first step then terminates. Unknown keys, a state out of range or a target that is not 3
finite numbers raise mgrl.Error.

    obs, info = env.reset(seed=1, options={"state": 12, "target": [0.1, 1.5, 0.4]})

MotionGraphVectorEnv steps num_envs such environments in one C++ call; an environment
whose episode ended is reset in the same step (its returned observation is the new
episode's; info["final"] marks which), as EnvPool does. Its reset takes the same options
and places every environment alike.
"""
import numpy as np

from . import _core

try:  # Gymnasium is not in Debian 12: the same API without it
    import gymnasium as _gym
    from gymnasium import spaces as _spaces

    _EnvBase = _gym.Env
except ImportError:  # pragma: no cover - depends on the machine
    _gym = None
    _spaces = None
    _EnvBase = object


class Discrete:
    """{0, ..., n - 1}: gymnasium.spaces.Discrete's fields when Gymnasium is absent."""

    def __init__(self, n, seed=None):
        self.n = int(n)
        self.shape = ()
        self.dtype = np.dtype(np.int64)
        self._rng = np.random.default_rng(seed)

    def sample(self, mask=None):
        if mask is None:
            return int(self._rng.integers(self.n))
        legal = np.flatnonzero(mask)
        return int(self._rng.choice(legal))

    def contains(self, x):
        return isinstance(x, (int, np.integer)) and 0 <= int(x) < self.n

    def seed(self, seed=None):
        self._rng = np.random.default_rng(seed)

    def __repr__(self):
        return f"Discrete({self.n})"


class Box:
    """Real vectors between low and high: gymnasium.spaces.Box's fields when absent."""

    def __init__(self, low, high, shape, dtype=np.float32):
        self.shape = tuple(shape)
        self.dtype = np.dtype(dtype)
        self.low = np.broadcast_to(np.asarray(low, dtype=self.dtype), self.shape).copy()
        self.high = np.broadcast_to(np.asarray(high, dtype=self.dtype), self.shape).copy()

    def contains(self, x):
        x = np.asarray(x)
        return x.shape == self.shape and bool(np.all(x >= self.low) and np.all(x <= self.high))

    def __repr__(self):
        return f"Box({self.low.min()}, {self.high.max()}, {self.shape}, {self.dtype})"


class Dict:
    """Named spaces: gymnasium.spaces.Dict's fields when absent."""

    def __init__(self, spaces):
        self.spaces = dict(spaces)

    def __getitem__(self, key):
        return self.spaces[key]

    def contains(self, x):
        return isinstance(x, dict) and x.keys() == self.spaces.keys() and all(
            self.spaces[k].contains(v) for k, v in x.items())

    def __repr__(self):
        return "Dict(" + ", ".join(f"{k}: {v!r}" for k, v in self.spaces.items()) + ")"


def _discrete(n):
    return _spaces.Discrete(n) if _spaces else Discrete(n)


def _box(low, high, shape):
    return _spaces.Box(low=low, high=high, shape=shape, dtype=np.float32) if _spaces else Box(low, high, shape)


def _dict(spaces):
    return _spaces.Dict(spaces) if _spaces else Dict(spaces)


def _observation_space(episodes):
    # Coordinates inside the grid lie within its vertices' range, axis by axis.
    bounds = episodes.bounds.astype(np.float32)
    return _dict({
        "state": _discrete(episodes.states),
        "target": _box(-np.inf, np.inf, (3,)),
        "coordinates": _box(bounds[:, 0], bounds[:, 1], (episodes.dimension,)),
    })


_OPTIONS = ("state", "target")


def _placement(options):
    """(state, target) from reset's options, None for what they leave out."""
    if options is None:
        return None, None
    if not isinstance(options, dict):
        raise _core.Error(f"options: expected None or a dict with keys {_OPTIONS}, found an object of type "
                          f"{type(options).__name__}")
    for key in options:
        if key not in _OPTIONS:
            raise _core.Error(f"options[{key!r}]: expected one of the keys {_OPTIONS}, found {key!r}")
    return options.get("state"), options.get("target")


def _session(scenario, data, cache, sets):
    if isinstance(scenario, _core.Session):
        return scenario
    return _core.Session(scenario, data=data, cache=cache, sets=sets)


class MotionGraphEnv(_EnvBase):
    """One avatar and one target: Gymnasium's Env API on a behaviour of a scenario.

    scenario may be a path (opened with data, cache and sets as on the command line) or an
    mgrl.Session already open (its graph is shared, not loaded again)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(self, scenario, behavior, data=None, cache=None, sets=None, max_seconds=10.0,
                 end_on_success=False, render_mode=None, render_size=160):
        if render_mode not in (None, "rgb_array"):
            raise _core.Error(f"render_mode: expected None or 'rgb_array', found {render_mode!r}")
        self.session = _session(scenario, data, cache, sets)
        self.behavior = behavior
        self._episodes = _core.Episodes(self.session, behavior, 1, float(max_seconds), bool(end_on_success))
        self.action_space = _discrete(self._episodes.max_actions)
        self.observation_space = _observation_space(self._episodes)
        self.render_mode = render_mode
        self.render_size = int(render_size)
        self._last = None

    def _observation(self):
        state, target, coordinates, mask = self._episodes.observe(0)
        return {"state": state, "target": target, "coordinates": coordinates}, mask

    def reset(self, *, seed=None, options=None):
        """A new episode, seeded when seed is given, placed as options says (the module's
        docstring): {"state": int, "target": (x, y, z)}, either or both."""
        state, target = _placement(options)
        if _gym is not None:
            super().reset(seed=seed)
        self._episodes.reset(0, seed, state, target)
        obs, mask = self._observation()
        self._last = obs
        return obs, {"action_mask": mask, "success": False, "seconds": 0.0}

    def step(self, action):
        reward, terminated, truncated, success, seconds = self._episodes.step(0, int(action))
        obs, mask = self._observation()
        self._last = obs
        return obs, float(reward), bool(terminated), bool(truncated), {
            "action_mask": mask, "success": bool(success), "seconds": seconds}

    def render(self):
        """A top-down picture (render_size pixels square, uint8 RGB): the avatar at the
        centre facing up, the behaviour's grid as grey dots, the target in red."""
        if self.render_mode != "rgb_array":
            return None
        return draw_top_down(self._episodes, self._last, self.render_size)

    def close(self):
        pass


class MotionGraphVectorEnv:
    """num_envs MotionGraphEnv episodes stepped in one C++ call (EnvPool-style autoreset:
    an ended episode restarts within the same step; info["final"] marks those)."""

    def __init__(self, scenario, behavior, num_envs, data=None, cache=None, sets=None, max_seconds=10.0,
                 end_on_success=False):
        self.session = _session(scenario, data, cache, sets)
        self.behavior = behavior
        self._episodes = _core.Episodes(self.session, behavior, int(num_envs), float(max_seconds),
                                        bool(end_on_success))
        self.num_envs = self._episodes.count
        self.single_action_space = _discrete(self._episodes.max_actions)
        self.single_observation_space = _observation_space(self._episodes)

    def _observations(self):
        state, target, coordinates, mask = self._episodes.observe_all()
        return {"state": state, "target": target, "coordinates": coordinates}, mask

    def reset(self, *, seed=None, options=None):
        """Every environment restarted; environment i seeded with seed + i when seed is given.
        options places every environment's start alike, as MotionGraphEnv.reset's does."""
        state, target = _placement(options)
        self._episodes.reset_all(seed, state, target)
        obs, mask = self._observations()
        return obs, {"action_mask": mask}

    def step(self, actions):
        reward, terminated, truncated, success = self._episodes.step_all(actions)
        obs, mask = self._observations()
        return obs, reward, terminated, truncated, {
            "action_mask": mask, "success": success, "final": terminated | truncated}

    def close(self):
        pass


def draw_top_down(episodes, obs, size):
    """The picture MotionGraphEnv.render() returns."""
    image = np.full((size, size, 3), 255, dtype=np.uint8)
    # The grid's reach sets the scale: its farthest vertex at 45 % of the picture.
    reach = episodes.reach
    scale = 0.45 * size / max(reach, 1e-6)
    centre = size / 2

    def pixel(x, z):  # avatar frame: +z ahead (up in the picture), +x to the left
        return int(round(centre - x * scale)), int(round(centre - z * scale))

    def disc(cx, cy, radius, colour):
        y, x = np.ogrid[:size, :size]
        image[(x - cx) ** 2 + (y - cy) ** 2 <= radius ** 2] = colour

    # The grid's ring of reach, as grey dots every 5 degrees.
    for angle in np.linspace(0, 2 * np.pi, 72, endpoint=False):
        px, py = pixel(reach * np.sin(angle), reach * np.cos(angle))
        if 0 <= px < size and 0 <= py < size:
            image[py, px] = (170, 170, 170)
    # The avatar: a blue disc with a line ahead.
    disc(centre, centre, max(2, size // 32), (40, 90, 200))
    for t in np.linspace(0, 0.35 * reach, 20):
        px, py = pixel(0.0, t)
        image[max(0, min(size - 1, py)), max(0, min(size - 1, px))] = (40, 90, 200)
    if obs is not None:
        x, _, z = (float(v) for v in obs["target"])
        px, py = pixel(x, z)
        disc(px, py, max(2, size // 40), (220, 40, 40))
    return image
