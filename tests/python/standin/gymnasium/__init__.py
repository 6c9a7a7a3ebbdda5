"""A stand-in for the few names of Gymnasium that mgrl.env imports (Gymnasium is not in
Debian 12). tests/python/test_gymnasium.py puts it on the path only to check that, when
Gymnasium is importable, mgrl's environments subclass its Env and VectorEnv and use its
spaces, and still pass the rules of tests/python/gym_rules.py. Not Gymnasium: classes with
its names and the members those rules use, nothing more."""
import numpy as np


class Env:
    metadata = {"render_modes": []}
    render_mode = None
    spec = None
    _np_random = None
    _np_random_seed = None

    @property
    def np_random(self):
        if self._np_random is None:
            self._np_random, self._np_random_seed = np.random.default_rng(), -1
        return self._np_random

    @property
    def np_random_seed(self):
        return self._np_random_seed

    @property
    def unwrapped(self):
        return self

    def reset(self, *, seed=None, options=None):
        if seed is not None:
            self._np_random, self._np_random_seed = np.random.default_rng(seed), seed

    def close(self):
        pass


from . import spaces, vector  # noqa: E402,F401 - after Env, which vector's VectorEnv extends
