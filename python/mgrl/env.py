"""One behaviour of a scenario as a reinforcement-learning environment with Gymnasium's
API (its Env and, batched, its VectorEnv), stepped in C++
(framework/include/mgrl/session/episodes.hpp says what a step does).

    env = mgrl.MotionGraphEnv("boxing", "hit")
    obs, info = env.reset(seed=1)
    while True:
        a = agent(obs, info["action_mask"])     # an index into the state's out-actions
        obs, reward, terminated, truncated, info = env.step(a)
        if terminated or truncated:
            break

Observation: a dict, "state" (the graph state, int), "target" (the target's position in
the avatar's frame, x, y, z in metres, float32) and "coordinates" (the same target in the
behaviour's grid coordinates, e.g. angle, distance, height; float32). The observation
space holds every observation, terminal ones included: a target that has left the grid
has a distance beyond the grid's reach, so the coordinates' space is each axis' whole
range (angles a whole turn, distances from 0, heights unbounded; speed, opponent and turn
layers their layers' values). `grid_axes` names the coordinates' axes ("angle",
"distance", ...) and `grid_bounds` gives the grid's own range on each, (D, 2).

Actions: Discrete(the most out-actions any state has). In a state with n out-actions,
indices 0..n-1 are its actions and info["action_mask"] (int8, as
Discrete.sample(mask=) takes it) marks them. Every index of the action space is valid, as
Gymnasium requires: one past n plays out-action index % n (illegal_actions="wrap", the
default), or raises mgrl.Error with illegal_actions="raise".

Reward: the behaviour's reward of the action from where the target is, computed at the
target itself. The tabulated problem (Session.problem) holds the same reward at the grid's
vertices; between vertices the environment's is exact where the table's is interpolated, so
it may exceed every tabulated value (a punch landing between two vertices).

Episodes: terminated when the target leaves the behaviour's grid (the tabulated problem's
edge: no future value beyond it) or, with end_on_success=True, when its success criterion
is met (info["success"] says when it is met either way); truncated after max_seconds of
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

MotionGraphVectorEnv steps num_envs such environments in one C++ call, with Gymnasium's
same-step autoreset (metadata["autoreset_mode"] is AutoresetMode.SAME_STEP): an
environment whose episode ended is reset within the step that ended it, so the returned
observation is the new episode's, and info["final_obs"] holds where each step led (for
an ended episode, its last observation; info["_final_obs"] marks those), which is what a
learner bootstraps a truncated episode from. Its reset takes the same options and places
every environment alike.

With Gymnasium installed the classes are gymnasium.Env and gymnasium.vector.VectorEnv and
the spaces Gymnasium's; without it, the module's own classes of the same names and fields.
"""
import enum
import numbers

import numpy as np

from . import _core

try:  # Gymnasium is not in Debian 12: the same API without it
    import gymnasium as _gym
    from gymnasium import spaces as _spaces
    from gymnasium.vector import VectorEnv as _VectorEnvBase
    from gymnasium.vector.utils import batch_space as _batch_space

    _EnvBase = _gym.Env
except ImportError:
    _gym = None
    _spaces = None

try:
    from gymnasium.vector import AutoresetMode
except ImportError:

    class AutoresetMode(enum.Enum):
        """When a vector environment resets an ended episode, as gymnasium.vector.AutoresetMode
        (Gymnasium 1.1) names it: NEXT_STEP, SAME_STEP (MotionGraphVectorEnv's) or DISABLED."""

        NEXT_STEP = "NextStep"
        SAME_STEP = "SameStep"
        DISABLED = "Disabled"


def _rng(seed=None):
    """A NumPy generator as Gymnasium's seeding.np_random makes it: PCG64 from the seed."""
    if seed is not None and not (isinstance(seed, numbers.Integral) and seed >= 0):
        raise _core.Error(f"seed: expected None or a non-negative integer, found {seed!r}")
    return np.random.Generator(np.random.PCG64(seed))


class Space:
    """A set of values with a random generator: gymnasium.spaces.Space's fields when
    Gymnasium is absent.

    Parameters
    ----------
    shape : tuple[int, ...] | None
        The shape of its values (None for a Dict).
    dtype : numpy.typing.DTypeLike
        Their NumPy dtype (None for a Dict).
    seed : int | None
        Seeds np_random.

    Attributes
    ----------
    shape : tuple[int, ...] | None
        The shape of its values.
    dtype : numpy.dtype[typing.Any] | None
        Their dtype.
    """

    def __init__(self, shape, dtype, seed=None):
        self.shape = None if shape is None else tuple(shape)
        self.dtype = None if dtype is None else np.dtype(dtype)
        self._np_random = None if seed is None else _rng(seed)

    @property
    def np_random(self):
        """The space's generator: sample() draws from it. Made on first use.

        Returns
        -------
        numpy.random.Generator
        """
        if self._np_random is None:
            self._np_random = _rng()
        return self._np_random

    def seed(self, seed=None):
        """Seeds the generator.

        Parameters
        ----------
        seed : int | None
            The seed; None draws one from the system.

        Returns
        -------
        list[int | None]
            [seed], as Gymnasium's.
        """
        self._np_random = _rng(seed)
        return [seed]

    def sample(self, mask=None):
        """A random element.

        Parameters
        ----------
        mask : typing.Any
            What the space allows (per kind of space), or None.

        Returns
        -------
        typing.Any
        """
        raise NotImplementedError

    def contains(self, x):
        """Whether x is an element.

        Parameters
        ----------
        x : typing.Any
            A value.

        Returns
        -------
        bool
        """
        raise NotImplementedError

    def __contains__(self, x):
        """x in space: contains(x).

        Parameters
        ----------
        x : typing.Any
            A value.

        Returns
        -------
        bool
        """
        return self.contains(x)


class Discrete(Space):
    """{start, ..., start + n - 1}: gymnasium.spaces.Discrete when Gymnasium is absent.

    Parameters
    ----------
    n : int
        How many elements.
    seed : int | None
        Seeds np_random.
    start : int
        The smallest element.

    Attributes
    ----------
    n : numpy.int64
        How many elements.
    start : numpy.int64
        The smallest.
    """

    def __init__(self, n, seed=None, start=0):
        super().__init__((), np.int64, seed)
        self.n = np.int64(n)
        self.start = np.int64(start)

    def sample(self, mask=None):
        """A uniformly random element, or one of those a mask allows.

        Parameters
        ----------
        mask : numpy.typing.NDArray[numpy.int8] | None
            Shape (n,), 1 where allowed (MotionGraphEnv's info["action_mask"]).

        Returns
        -------
        numpy.int64
            The element; start if the mask allows none.
        """
        if mask is None:
            return self.start + self.np_random.integers(self.n)
        mask = np.asarray(mask)
        if mask.dtype != np.int8 or mask.shape != (self.n,):
            raise ValueError(f"mask: expected an int8 array of shape ({self.n},), found {mask.dtype} {mask.shape}")
        legal = np.flatnonzero(mask)
        return self.start + (self.np_random.choice(legal) if len(legal) else np.int64(0))

    def contains(self, x):
        """Whether x is an integer in [start, start + n).

        Parameters
        ----------
        x : typing.Any
            A value.

        Returns
        -------
        bool
        """
        if isinstance(x, (numbers.Integral, np.integer)):
            value = int(x)
        elif isinstance(x, np.ndarray) and x.shape == () and x.dtype.kind in "iu":
            value = int(x)
        else:
            return False
        return bool(self.start <= value < self.start + self.n)

    def __eq__(self, other):
        return isinstance(other, Discrete) and self.n == other.n and self.start == other.start

    def __repr__(self):
        return f"Discrete({self.n})"


class MultiDiscrete(Space):
    """Integer arrays whose element i lies in [0, nvec[i]): gymnasium.spaces.MultiDiscrete
    when Gymnasium is absent (a batch of Discrete spaces).

    Parameters
    ----------
    nvec : numpy.typing.ArrayLike
        Each element's count of values.
    seed : int | None
        Seeds np_random.

    Attributes
    ----------
    nvec : numpy.typing.NDArray[numpy.int64]
        Each element's count of values.
    """

    def __init__(self, nvec, seed=None):
        self.nvec = np.asarray(nvec, dtype=np.int64)
        super().__init__(self.nvec.shape, np.int64, seed)

    def sample(self, mask=None):
        """Uniformly random values, or one value each mask allows.

        Parameters
        ----------
        mask : collections.abc.Sequence[numpy.typing.NDArray[numpy.int8]] | None
            One int8 mask per element (MotionGraphVectorEnv's info["action_mask"] rows).

        Returns
        -------
        numpy.typing.NDArray[numpy.int64]
        """
        if mask is None:
            return (self.np_random.random(self.shape) * self.nvec).astype(np.int64)
        out = np.zeros(self.shape, dtype=np.int64)
        for i, (n, m) in enumerate(zip(self.nvec, mask)):
            legal = np.flatnonzero(np.asarray(m)[:n])
            out[i] = self.np_random.choice(legal) if len(legal) else 0
        return out

    def contains(self, x):
        """Whether x is an integer array of the shape with each value in range.

        Parameters
        ----------
        x : typing.Any
            A value.

        Returns
        -------
        bool
        """
        x = np.asarray(x) if isinstance(x, (list, tuple)) else x
        return (isinstance(x, np.ndarray) and x.shape == self.shape and x.dtype.kind in "iu"
                and bool(np.all((0 <= x) & (x < self.nvec))))

    def __eq__(self, other):
        return isinstance(other, MultiDiscrete) and np.array_equal(self.nvec, other.nvec)

    def __repr__(self):
        return f"MultiDiscrete({self.nvec})"


class Box(Space):
    """Real arrays between low and high, bounds included: gymnasium.spaces.Box when
    Gymnasium is absent.

    Parameters
    ----------
    low : numpy.typing.ArrayLike
        The lower bounds (broadcast to shape; -inf for none).
    high : numpy.typing.ArrayLike
        The upper bounds (inf for none).
    shape : tuple[int, ...]
        The values' shape.
    dtype : numpy.typing.DTypeLike
        Their dtype.
    seed : int | None
        Seeds np_random.

    Attributes
    ----------
    low : numpy.typing.NDArray[typing.Any]
        The lower bounds, of the shape.
    high : numpy.typing.NDArray[typing.Any]
        The upper bounds.
    """

    def __init__(self, low, high, shape, dtype=np.float32, seed=None):
        super().__init__(shape, dtype, seed)
        self.low = np.broadcast_to(np.asarray(low, dtype=self.dtype), self.shape).copy()
        self.high = np.broadcast_to(np.asarray(high, dtype=self.dtype), self.shape).copy()

    def sample(self, mask=None):
        """A random array: uniform where both bounds are finite, normal where neither is,
        and exponential from the finite bound where only one is, as Gymnasium's.

        Parameters
        ----------
        mask : None
            Not used (Gymnasium's Box takes none).

        Returns
        -------
        numpy.typing.NDArray[typing.Any]
        """
        low, high = self.low.astype(np.float64), self.high.astype(np.float64)
        bounded_low, bounded_high = np.isfinite(low), np.isfinite(high)
        out = self.np_random.normal(size=self.shape)
        both = bounded_low & bounded_high
        out[both] = self.np_random.uniform(low[both], high[both])
        only_low = bounded_low & ~bounded_high
        out[only_low] = low[only_low] + self.np_random.exponential(size=only_low.sum())
        only_high = bounded_high & ~bounded_low
        out[only_high] = high[only_high] - self.np_random.exponential(size=only_high.sum())
        return out.astype(self.dtype)

    def contains(self, x):
        """Whether x is an array of the shape, a dtype that casts safely, within the bounds.

        Parameters
        ----------
        x : typing.Any
            A value.

        Returns
        -------
        bool
        """
        if not isinstance(x, np.ndarray):
            x = np.asarray(x, dtype=self.dtype)
        return (x.shape == self.shape and np.can_cast(x.dtype, self.dtype)
                and bool(np.all(x >= self.low) and np.all(x <= self.high)))

    def __eq__(self, other):
        return (isinstance(other, Box) and self.shape == other.shape and self.dtype == other.dtype
                and np.array_equal(self.low, other.low) and np.array_equal(self.high, other.high))

    def __repr__(self):
        return f"Box({self.low.min()}, {self.high.max()}, {self.shape}, {self.dtype})"


class Dict(Space):
    """Named spaces: gymnasium.spaces.Dict when Gymnasium is absent.

    Parameters
    ----------
    spaces : collections.abc.Mapping[str, Space]
        The spaces by name.
    seed : int | None
        Seeds np_random.

    Attributes
    ----------
    spaces : dict[str, Space]
        The spaces by name.
    """

    def __init__(self, spaces, seed=None):
        super().__init__(None, None, seed)
        self.spaces = dict(spaces)

    def __getitem__(self, key):
        """The space of that name.

        Parameters
        ----------
        key : str
            A name.

        Returns
        -------
        Space
        """
        return self.spaces[key]

    def keys(self):
        """The names.

        Returns
        -------
        collections.abc.KeysView[str]
        """
        return self.spaces.keys()

    def seed(self, seed=None):
        """Seeds this space, then each of its spaces from seeds it draws, in key order.

        Parameters
        ----------
        seed : int | None
            The seed.

        Returns
        -------
        list[int | None]
            seed, then each space's.
        """
        super().seed(seed)
        seeds = [int(s) for s in self._np_random.integers(2 ** 31, size=len(self.spaces))]
        return [seed] + [space.seed(s)[0] for space, s in zip(self.spaces.values(), seeds)]

    def sample(self, mask=None):
        """A random element of each space.

        Parameters
        ----------
        mask : None
            Not used.

        Returns
        -------
        dict[str, typing.Any]
        """
        return {k: space.sample() for k, space in self.spaces.items()}

    def contains(self, x):
        """Whether x is a dict with the same names, each value in its space.

        Parameters
        ----------
        x : typing.Any
            A value.

        Returns
        -------
        bool
        """
        return isinstance(x, dict) and x.keys() == self.spaces.keys() and all(
            self.spaces[k].contains(v) for k, v in x.items())

    def __eq__(self, other):
        return isinstance(other, Dict) and self.spaces == other.spaces

    def __repr__(self):
        return "Dict(" + ", ".join(f"{k!r}: {v!r}" for k, v in self.spaces.items()) + ")"


def batch_space(space, n):
    """n of a space as one space (gymnasium.vector.utils.batch_space when Gymnasium is
    absent): Discrete becomes MultiDiscrete, Box gains a leading axis, Dict batches each.

    Parameters
    ----------
    space : Space
        A Discrete, Box or Dict space.
    n : int
        How many.

    Returns
    -------
    Space
    """
    if isinstance(space, Discrete):
        return MultiDiscrete(np.full(n, space.n))
    if isinstance(space, Box):
        return Box(np.repeat(space.low[None], n, axis=0), np.repeat(space.high[None], n, axis=0),
                   (n,) + space.shape, space.dtype)
    if isinstance(space, Dict):
        return Dict({k: batch_space(s, n) for k, s in space.spaces.items()})
    raise TypeError(f"batch_space: expected a Discrete, Box or Dict space, found {type(space).__name__}")


class _Seeded:
    """What Gymnasium's Env and VectorEnv have beside step and reset, when it is absent:
    np_random (seeded by reset(seed=...)), np_random_seed, spec, unwrapped, render_mode,
    metadata, close and use in a with statement."""

    metadata = {"render_modes": []}
    render_mode = None
    spec = None
    _np_random = None
    _np_random_seed = None

    @property
    def np_random(self):
        """The environment's NumPy generator: seeded by reset(seed=...), else made on first use.

        Returns
        -------
        numpy.random.Generator
        """
        if self._np_random is None:
            self._np_random = _rng()
            self._np_random_seed = -1
        return self._np_random

    @np_random.setter
    def np_random(self, value):
        self._np_random = value
        self._np_random_seed = -1

    @property
    def np_random_seed(self):
        """The seed np_random was made from.

        Returns
        -------
        int
            The seed reset() was last given; -1 when np_random was not made from one.
        """
        if self._np_random is None:
            self.np_random  # noqa: B018 - made on first use
        return self._np_random_seed

    @property
    def unwrapped(self):
        """The environment under any wrappers: here, itself.

        Returns
        -------
        typing.Self
        """
        return self

    def reset(self, *, seed=None, options=None):
        if seed is not None:
            self._np_random = _rng(seed)
            self._np_random_seed = seed

    def close(self):
        """Nothing to release: the C++ episodes go with the object.

        Returns
        -------
        None
        """

    def get_wrapper_attr(self, name):
        """An attribute of the environment, as Gymnasium's wrappers look one up.

        Parameters
        ----------
        name : str
            Its name.

        Returns
        -------
        typing.Any
        """
        return getattr(self, name)

    def __enter__(self):
        """The environment, for a with statement (closed at its end).

        Returns
        -------
        typing.Self
        """
        return self

    def __exit__(self, *args):
        """Closes the environment.

        Parameters
        ----------
        args : object
            The exception's type, value and traceback, if any.

        Returns
        -------
        bool
            False: an exception goes on.
        """
        self.close()
        return False


if _gym is None:
    _EnvBase = _Seeded
    _VectorEnvBase = _Seeded
    _batch_space = batch_space
else:  # pragma: no cover - depends on the machine
    Discrete, MultiDiscrete, Box, Dict = (_spaces.Discrete, _spaces.MultiDiscrete, _spaces.Box,  # noqa: F811
                                          _spaces.Dict)


def _observation_space(episodes):
    domain = episodes.domain.astype(np.float32)
    return Dict({
        "state": Discrete(episodes.states),
        "target": Box(-np.inf, np.inf, (3,), np.float32),
        "coordinates": Box(domain[:, 0], domain[:, 1], (episodes.dimension,), np.float32),
    })


_OPTIONS = ("state", "target")
_ILLEGAL = ("wrap", "raise")


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


def _illegal(illegal_actions):
    if illegal_actions not in _ILLEGAL:
        raise _core.Error(f"illegal_actions: expected 'wrap' or 'raise', found {illegal_actions!r}")
    return illegal_actions


class MotionGraphEnv(_EnvBase):
    """One avatar and one target: Gymnasium's Env on a behaviour of a scenario (the module's
    docstring says what observations, actions, rewards and episodes are).

    Parameters
    ----------
    scenario : str | os.PathLike[str] | Session
        A scenario's path or shipped name, opened with data, cache and sets as on the
        command line, or a Session already open (its graph is shared, not loaded again).
    behavior : str
        The behaviour to play ("approach", "hit", ...).
    data : str | os.PathLike[str] | None
        As Session's.
    cache : str | os.PathLike[str] | None
        As Session's.
    sets : dict[str, object] | list[str] | None
        As Session's.
    max_seconds : float
        Seconds of motion after which an episode is truncated.
    end_on_success : bool
        Whether meeting the behaviour's success criterion terminates the episode.
    render_mode : str | None
        "rgb_array": render() returns a top-down picture; None: it returns None.
    render_size : int
        The picture's side in pixels.
    illegal_actions : str
        What an index past the state's out-actions does: "wrap" plays index % out-actions,
        "raise" raises mgrl.Error.

    Attributes
    ----------
    action_space : Discrete
        Discrete(the most out-actions any state has).
    observation_space : Dict
        "state" Discrete(S), "target" Box (3,), "coordinates" Box (D,).
    session : Session
        The session the episodes are played on.
    behavior : str
        The behaviour played.
    grid_axes : tuple[str, ...]
        The coordinates' axes ("angle", "distance", ...).
    grid_bounds : numpy.typing.NDArray[numpy.float64]
        (D, 2): the grid's own range on each axis.
    metadata : dict[str, typing.Any]
        "render_modes" and "render_fps", as Gymnasium's.
    render_mode : str | None
        As given.
    render_size : int
        As given.
    spec : None
        No registration spec (Gymnasium's gymnasium.make sets one).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(self, scenario, behavior, data=None, cache=None, sets=None, max_seconds=10.0,
                 end_on_success=False, render_mode=None, render_size=160, illegal_actions="wrap"):
        if render_mode not in (None, "rgb_array"):
            raise _core.Error(f"render_mode: expected None or 'rgb_array', found {render_mode!r}")
        self._illegal = _illegal(illegal_actions)
        self.session = _session(scenario, data, cache, sets)
        self.behavior = behavior
        self._episodes = _core.Episodes(self.session, behavior, 1, float(max_seconds), bool(end_on_success))
        self._degree = np.diff(self.session.graph["state_action_begin"]).astype(np.int64)
        self.action_space = Discrete(self._episodes.max_actions)
        self.observation_space = _observation_space(self._episodes)
        self.grid_axes = tuple(self._episodes.axes)
        self.grid_bounds = self._episodes.bounds
        self.render_mode = render_mode
        self.render_size = int(render_size)
        self._last = None

    def _observation(self):
        state, target, coordinates, mask = self._episodes.observe(0)
        return {"state": state, "target": target, "coordinates": coordinates}, mask

    def reset(self, *, seed=None, options=None):
        """Starts a new episode.

        Parameters
        ----------
        seed : int | None
            Seeds the episode's random numbers (and np_random); None goes on from the last.
        options : dict[str, typing.Any] | None
            {"state": int, "target": (x, y, z)}, either or both: the episode's start (the
            module's docstring).

        Returns
        -------
        tuple[dict[str, typing.Any], dict[str, typing.Any]]
            (observation, info): info has "action_mask" (int8), "success" (False) and
            "seconds" (0.0).

        Raises
        ------
        mgrl.Error
            Unknown options, a state out of range or a target not 3 finite numbers.
        """
        state, target = _placement(options)
        super().reset(seed=seed)
        self._episodes.reset(0, seed, state, target)
        obs, mask = self._observation()
        self._last = obs
        return obs, {"action_mask": mask, "success": False, "seconds": 0.0}

    def step(self, action):
        """Plays one action of the current state.

        Parameters
        ----------
        action : int | numpy.integer[typing.Any]
            An element of action_space: an index into the state's out-actions (past them,
            as illegal_actions says).

        Returns
        -------
        tuple[dict[str, typing.Any], float, bool, bool, dict[str, typing.Any]]
            (observation, reward, terminated, truncated, info): info has "action_mask"
            (int8, for the new state), "success" (the criterion met during this action) and
            "seconds" (of motion played in the episode).

        Raises
        ------
        mgrl.Error
            An action outside the action space (or past the out-actions with
            illegal_actions="raise").
        """
        choice = self._choice(action)
        reward, terminated, truncated, success, seconds = self._episodes.step(0, choice)
        obs, mask = self._observation()
        self._last = obs
        return obs, float(reward), bool(terminated), bool(truncated), {
            "action_mask": mask, "success": bool(success), "seconds": seconds}

    def _choice(self, action):
        if isinstance(action, (bool, np.bool_)) or not isinstance(action, (numbers.Integral, np.integer)):
            if not (isinstance(action, np.ndarray) and action.shape == () and action.dtype.kind in "iu"):
                raise _core.Error(f"action: expected an integer in [0, {self.action_space.n}), found {action!r}")
        choice = int(action)
        if self._illegal == "wrap" and 0 <= choice < self.action_space.n:
            state = self._last["state"] if self._last is not None else self._episodes.observe(0)[0]
            choice %= int(self._degree[state])
        return choice

    def render(self):
        """A top-down picture: the avatar at the centre facing up, the behaviour's grid as
        grey dots, the target in red.

        Returns
        -------
        numpy.typing.NDArray[numpy.uint8] | None
            (render_size, render_size, 3) RGB; None unless render_mode is "rgb_array".
        """
        if self.render_mode != "rgb_array":
            return None
        return draw_top_down(self._episodes, self._last, self.render_size)

    def close(self):
        """Nothing to release: the C++ episodes go with the object.

        Returns
        -------
        None
        """


class MotionGraphVectorEnv(_VectorEnvBase):
    """num_envs MotionGraphEnv episodes stepped in one C++ call: Gymnasium's VectorEnv with
    same-step autoreset (the module's docstring).

    Info, as Gymnasium's vector environments give it: each key an array over the
    environments with a boolean "_key" beside it saying which hold a value:
    "action_mask" (int8, (num_envs, max actions)), "success", and at the ends of
    episodes "final_obs" and "final_info".

    Parameters
    ----------
    scenario : str | os.PathLike[str] | Session
        As MotionGraphEnv's.
    behavior : str
        As MotionGraphEnv's.
    num_envs : int
        How many environments, in [1, 1000000].
    data : str | os.PathLike[str] | None
        As Session's.
    cache : str | os.PathLike[str] | None
        As Session's.
    sets : dict[str, object] | list[str] | None
        As Session's.
    max_seconds : float
        As MotionGraphEnv's.
    end_on_success : bool
        As MotionGraphEnv's.
    illegal_actions : str
        As MotionGraphEnv's.

    Attributes
    ----------
    num_envs : int
        How many environments.
    single_action_space : Discrete
        One environment's.
    single_observation_space : Dict
        One environment's.
    action_space : MultiDiscrete
        The batch's: one action per environment.
    observation_space : Dict
        The batch's: each of one environment's spaces with a leading num_envs axis.
    session : Session
        As MotionGraphEnv's.
    behavior : str
        As MotionGraphEnv's.
    grid_axes : tuple[str, ...]
        As MotionGraphEnv's.
    grid_bounds : numpy.typing.NDArray[numpy.float64]
        As MotionGraphEnv's.
    metadata : dict[str, typing.Any]
        "render_modes" (none) and "autoreset_mode" (AutoresetMode.SAME_STEP).
    render_mode : None
        No rendering.
    spec : None
        No registration spec.
    """

    metadata = {"render_modes": [], "autoreset_mode": AutoresetMode.SAME_STEP}

    def __init__(self, scenario, behavior, num_envs, data=None, cache=None, sets=None, max_seconds=10.0,
                 end_on_success=False, illegal_actions="wrap"):
        self._illegal = _illegal(illegal_actions)
        self.session = _session(scenario, data, cache, sets)
        self.behavior = behavior
        self._episodes = _core.Episodes(self.session, behavior, int(num_envs), float(max_seconds),
                                        bool(end_on_success))
        self._degree = np.diff(self.session.graph["state_action_begin"]).astype(np.int64)
        self.num_envs = self._episodes.count
        self.single_action_space = Discrete(self._episodes.max_actions)
        self.single_observation_space = _observation_space(self._episodes)
        self.action_space = _batch_space(self.single_action_space, self.num_envs)
        self.observation_space = _batch_space(self.single_observation_space, self.num_envs)
        self.grid_axes = tuple(self._episodes.axes)
        self.grid_bounds = self._episodes.bounds
        self._state = None

    def _observations(self):
        state, target, coordinates, mask = self._episodes.observe_all()
        self._state = state
        return {"state": state.astype(np.int64), "target": target, "coordinates": coordinates}, mask

    def _masks(self, states):
        width = int(self.single_action_space.n)
        return (np.arange(width)[None, :] < self._degree[states][:, None]).astype(np.int8)

    def reset(self, *, seed=None, options=None):
        """Restarts every environment.

        Parameters
        ----------
        seed : int | None
            Environment i is seeded with seed + i (and np_random with seed).
        options : dict[str, typing.Any] | None
            Places every environment's start alike, as MotionGraphEnv.reset's.

        Returns
        -------
        tuple[dict[str, numpy.typing.NDArray[typing.Any]], dict[str, typing.Any]]
            (observations, info): batched as observation_space; info["action_mask"] int8
            (num_envs, max actions).
        """
        state, target = _placement(options)
        super().reset(seed=seed)
        self._episodes.reset_all(seed, state, target)
        obs, mask = self._observations()
        every = np.ones(self.num_envs, dtype=bool)
        return obs, {"action_mask": mask, "_action_mask": every}

    def step(self, actions):
        """Plays one action in every environment.

        Parameters
        ----------
        actions : numpy.typing.ArrayLike
            Integers, shape (num_envs,): an element of action_space.

        Returns
        -------
        tuple[dict[str, numpy.typing.NDArray[typing.Any]], numpy.typing.NDArray[numpy.float32], numpy.typing.NDArray[numpy.bool_], numpy.typing.NDArray[numpy.bool_], dict[str, typing.Any]]
            (observations, rewards, terminations, truncations, info), arrays over the
            environments. An ended environment's observation is its new episode's; its last
            one is in info["final_obs"] (a batch like the observations, each row where that
            environment's step led; info["_final_obs"] marks the ended ones) and that
            step's info in info["final_info"] ("action_mask" of the state it led to,
            "success").

        Raises
        ------
        mgrl.Error
            Actions of the wrong shape or dtype, or outside the action space.
        """
        actions = self._choices(actions)
        reward, terminated, truncated, success, end_state, end_target, end_coordinates = \
            self._episodes.step_all(actions)
        obs, mask = self._observations()
        ended = terminated | truncated
        every = np.ones(self.num_envs, dtype=bool)
        final_obs = {"state": end_state.astype(np.int64), "target": end_target, "coordinates": end_coordinates}
        final_info = {"action_mask": self._masks(end_state), "_action_mask": ended.copy(),
                      "success": success.copy(), "_success": ended.copy()}
        return obs, reward, terminated, truncated, {
            "action_mask": mask, "_action_mask": every, "success": success, "_success": every,
            "final_obs": final_obs, "_final_obs": ended, "final_info": final_info, "_final_info": ended.copy()}

    def _choices(self, actions):
        if self._illegal == "raise" or self._state is None:
            return actions
        given = np.asarray(actions)
        if given.shape != (self.num_envs,) or given.dtype.kind not in "iu":
            return actions  # refused with the exact reason by the C++ step
        given = given.astype(np.int64)
        inside = (given >= 0) & (given < self.single_action_space.n)
        degree = self._degree[self._state]
        return np.where(inside, given % degree, given)

    def close(self, **kwargs):
        """Nothing to release: the C++ episodes go with the object.

        Parameters
        ----------
        kwargs : object
            Accepted as Gymnasium's VectorEnv.close accepts them; not used.

        Returns
        -------
        None
        """


def draw_top_down(episodes, obs, size):
    """The picture MotionGraphEnv.render() returns.

    Parameters
    ----------
    episodes : typing.Any
        The environment's C++ episodes (their grid's reach sets the scale).
    obs : dict[str, typing.Any] | None
        The observation to draw the target of.
    size : int
        The picture's side in pixels.

    Returns
    -------
    numpy.typing.NDArray[numpy.uint8]
        (size, size, 3) RGB.
    """
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
