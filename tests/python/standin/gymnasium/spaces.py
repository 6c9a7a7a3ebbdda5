"""The stand-in's gymnasium.spaces: Discrete, MultiDiscrete, Box and Dict with the members
tests/python/gym_rules.py uses (see the package's docstring)."""
import numpy as np


class Space:
    def __init__(self):
        self.np_random = np.random.default_rng()

    def seed(self, seed=None):
        self.np_random = np.random.default_rng(seed)
        return [seed]


class Discrete(Space):
    def __init__(self, n):
        super().__init__()
        self.n = np.int64(n)

    def sample(self, mask=None):
        if mask is None:
            return np.int64(self.np_random.integers(self.n))
        assert mask.dtype == np.int8 and mask.shape == (self.n,), "Gymnasium's Discrete takes an int8 mask"
        return np.int64(self.np_random.choice(np.flatnonzero(mask)))

    def contains(self, x):
        return isinstance(x, (int, np.integer)) and 0 <= int(x) < self.n

    def __eq__(self, other):
        return isinstance(other, Discrete) and self.n == other.n


class MultiDiscrete(Space):
    def __init__(self, nvec):
        super().__init__()
        self.nvec = np.asarray(nvec, dtype=np.int64)

    def sample(self, mask=None):
        return (self.np_random.random(self.nvec.shape) * self.nvec).astype(np.int64)

    def contains(self, x):
        return (isinstance(x, np.ndarray) and x.shape == self.nvec.shape and x.dtype.kind in "iu"
                and bool(np.all((x >= 0) & (x < self.nvec))))

    def __eq__(self, other):
        return isinstance(other, MultiDiscrete) and np.array_equal(self.nvec, other.nvec)


class Box(Space):
    def __init__(self, low, high, shape, dtype=np.float32):
        super().__init__()
        self.shape, self.dtype = tuple(shape), np.dtype(dtype)
        self.low = np.broadcast_to(np.asarray(low, dtype=self.dtype), self.shape).copy()
        self.high = np.broadcast_to(np.asarray(high, dtype=self.dtype), self.shape).copy()

    def sample(self, mask=None):
        return np.clip(self.np_random.normal(size=self.shape), self.low, self.high).astype(self.dtype)

    def contains(self, x):
        return (isinstance(x, np.ndarray) and x.shape == self.shape and np.can_cast(x.dtype, self.dtype)
                and bool(np.all((x >= self.low) & (x <= self.high))))

    def __eq__(self, other):
        return (isinstance(other, Box) and self.shape == other.shape and np.array_equal(self.low, other.low)
                and np.array_equal(self.high, other.high))


class Dict(Space):
    def __init__(self, spaces):
        super().__init__()
        self.spaces = dict(spaces)

    def __getitem__(self, key):
        return self.spaces[key]

    def sample(self, mask=None):
        return {k: s.sample() for k, s in self.spaces.items()}

    def contains(self, x):
        return isinstance(x, dict) and x.keys() == self.spaces.keys() and all(
            s.contains(x[k]) for k, s in self.spaces.items())

    def __eq__(self, other):
        return isinstance(other, Dict) and self.spaces == other.spaces
