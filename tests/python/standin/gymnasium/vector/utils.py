"""The stand-in's gymnasium.vector.utils.batch_space."""
import numpy as np

from .. import spaces


def batch_space(space, n):
    if isinstance(space, spaces.Discrete):
        return spaces.MultiDiscrete(np.full(n, space.n))
    if isinstance(space, spaces.Box):
        return spaces.Box(np.repeat(space.low[None], n, axis=0), np.repeat(space.high[None], n, axis=0),
                          (n,) + space.shape, space.dtype)
    return spaces.Dict({k: batch_space(s, n) for k, s in space.spaces.items()})
