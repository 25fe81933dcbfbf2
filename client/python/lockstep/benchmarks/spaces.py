"""The few Gymnasium spaces the environments need (there is no Gymnasium package here):
Box, Discrete and Dict with Gymnasium's names, attributes and behaviour (`sample()` from
the space's own seeded generator, `contains(x)` / `x in space`, `seed()`, `shape`, `dtype`)."""
import numpy as np


class Space:
    def __init__(self, shape=None, dtype=None, seed=None):
        self.shape = None if shape is None else tuple(shape)
        self.dtype = None if dtype is None else np.dtype(dtype)
        self._np_random = np.random.default_rng(seed)

    @property
    def np_random(self):
        return self._np_random

    def seed(self, seed=None):
        self._np_random = np.random.default_rng(seed)
        return [seed]

    def __contains__(self, x):
        return self.contains(x)


class Box(Space):
    """A box in R^n: low <= x <= high, element-wise."""

    def __init__(self, low, high, shape=None, dtype=np.float32, seed=None):
        dtype = np.dtype(dtype)
        if shape is None:
            shape = np.broadcast(np.asarray(low), np.asarray(high)).shape
        self.low = np.broadcast_to(np.asarray(low, dtype=dtype), shape).copy()
        self.high = np.broadcast_to(np.asarray(high, dtype=dtype), shape).copy()
        if np.any(self.low > self.high):
            raise ValueError('Box: low > high')
        super().__init__(shape, dtype, seed)

    def sample(self):
        low = np.where(np.isfinite(self.low), self.low, -1e6)
        high = np.where(np.isfinite(self.high), self.high, 1e6)
        return self.np_random.uniform(low, high, self.shape).astype(self.dtype)

    def contains(self, x):
        x = np.asarray(x)
        return x.shape == self.shape and bool(np.all(x >= self.low) and np.all(x <= self.high))

    def __repr__(self):
        return 'Box(%s, %s, %s, %s)' % (self.low.min(), self.high.max(), self.shape, self.dtype)

    def __eq__(self, o):
        return isinstance(o, Box) and self.shape == o.shape and np.array_equal(self.low, o.low) and \
            np.array_equal(self.high, o.high)


class Discrete(Space):
    """{start, ..., start + n - 1}."""

    def __init__(self, n, seed=None, start=0):
        if int(n) <= 0:
            raise ValueError('Discrete: n must be positive')
        self.n = int(n)
        self.start = int(start)
        super().__init__((), np.int64, seed)

    def sample(self):
        return int(self.start + self.np_random.integers(self.n))

    def contains(self, x):
        if isinstance(x, (np.generic, np.ndarray)) and np.asarray(x).shape == ():
            x = int(x)
        return isinstance(x, int) and self.start <= x < self.start + self.n

    def __repr__(self):
        return 'Discrete(%d)' % self.n if self.start == 0 else 'Discrete(%d, start=%d)' % (self.n, self.start)

    def __eq__(self, o):
        return isinstance(o, Discrete) and self.n == o.n and self.start == o.start


class Dict(Space):
    """A dictionary of spaces, in the order given (sorted by key when given a plain dict, as
    Gymnasium does)."""

    def __init__(self, spaces=None, seed=None, **kwargs):
        spaces = dict(spaces or {}, **kwargs)
        if not isinstance(spaces, dict):
            raise TypeError('Dict: a mapping of spaces')
        self.spaces = {k: spaces[k] for k in sorted(spaces)}
        super().__init__(None, None, seed)
        if seed is not None:
            self.seed(seed)

    def seed(self, seed=None):
        super().seed(seed)
        for i, s in enumerate(self.spaces.values()):
            s.seed(None if seed is None else seed + i)
        return [seed]

    def sample(self):
        return {k: s.sample() for k, s in self.spaces.items()}

    def contains(self, x):
        return isinstance(x, dict) and set(x) == set(self.spaces) and all(s.contains(x[k]) for k, s in self.spaces.items())

    def __getitem__(self, key):
        return self.spaces[key]

    def keys(self):
        return self.spaces.keys()

    def __repr__(self):
        return 'Dict(%s)' % ', '.join('%r: %r' % kv for kv in self.spaces.items())
