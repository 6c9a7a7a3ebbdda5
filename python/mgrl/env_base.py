"""What mgrl.env builds on: Gymnasium's Env, VectorEnv, spaces, batch_space and
AutoresetMode where Gymnasium is importable; without it (it is not in Debian 12) the
module's own of the same names and fields (mgrl.spaces, and _Seeded here: what Env and
VectorEnv have beside step and reset)."""
import enum

from .spaces import Box, Dict, Discrete, MultiDiscrete, Space, _rng, batch_space  # noqa: F401 - re-exported

try:
    import gymnasium as _gym
    from gymnasium import spaces as _spaces
    from gymnasium.vector import VectorEnv as _VectorEnvBase
    from gymnasium.vector.utils import batch_space as _batch_space
except ImportError:
    _gym = None

try:
    from gymnasium.vector import AutoresetMode
except ImportError:

    class AutoresetMode(enum.Enum):
        """When a vector environment resets an ended episode, as gymnasium.vector.AutoresetMode
        (Gymnasium 1.1) names it: NEXT_STEP, SAME_STEP (MotionGraphVectorEnv's) or DISABLED."""

        NEXT_STEP = "NextStep"
        SAME_STEP = "SameStep"
        DISABLED = "Disabled"


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
    _EnvBase = _gym.Env
    Discrete, MultiDiscrete, Box, Dict = (_spaces.Discrete, _spaces.MultiDiscrete, _spaces.Box,  # noqa: F811
                                          _spaces.Dict)
