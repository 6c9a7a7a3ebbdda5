"""Gymnasium's spaces for when Gymnasium is absent (it is not in Debian 12): the ones
MotionGraphEnv and MotionGraphVectorEnv use (Space, Discrete, MultiDiscrete, Box, Dict,
batch_space). mgrl.env takes Gymnasium's own where it is importable; mgrl.env_base has
the rest of Gymnasium's names it needs."""
import numbers

import numpy as np

from . import _core

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
