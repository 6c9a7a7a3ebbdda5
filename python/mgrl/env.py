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
import numbers

import numpy as np

from . import _core

from .env_base import (AutoresetMode, Box, Dict, Discrete, MultiDiscrete, Space, _Seeded,  # noqa: F401 - mgrl.env's names
                       batch_space, _EnvBase, _VectorEnvBase, _batch_space, _gym)


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
