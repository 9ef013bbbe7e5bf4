"""Observation and action spaces: gymnasium.spaces when gymnasium is importable, otherwise
two small classes with the same constructor and the parts of the API environments and
agents use (shape, dtype, low, high, contains, sample, seed)."""

from __future__ import annotations

from typing import Mapping

import numpy as np

try:
    import gymnasium.spaces as _gym_spaces
except ImportError:  # gymnasium is optional
    _gym_spaces = None


class _Box:
    """A box in R^n: low <= x <= high, componentwise."""

    def __init__(self, low, high, shape=None, dtype=np.float64, seed=None):
        self.dtype = np.dtype(dtype)
        shape = tuple(shape) if shape is not None else np.shape(low)
        self.shape = shape
        self.low = np.broadcast_to(np.asarray(low, dtype=self.dtype), shape).copy()
        self.high = np.broadcast_to(np.asarray(high, dtype=self.dtype), shape).copy()
        self._rng = np.random.default_rng(seed)

    def seed(self, seed=None):
        self._rng = np.random.default_rng(seed)
        return [seed]

    def contains(self, x) -> bool:
        x = np.asarray(x)
        return (x.shape == self.shape and np.can_cast(x.dtype, self.dtype)
                and bool(np.all(x >= self.low)) and bool(np.all(x <= self.high)))

    def __contains__(self, x) -> bool:
        return self.contains(x)

    def sample(self):
        """Uniform where bounded on both sides, normal where unbounded (as gymnasium)."""
        low = np.where(np.isfinite(self.low), self.low, 0.0)
        high = np.where(np.isfinite(self.high), self.high, 0.0)
        bounded = np.isfinite(self.low) & np.isfinite(self.high)
        x = np.where(bounded, self._rng.uniform(low, high, self.shape),
                     self._rng.normal(size=self.shape))
        return x.astype(self.dtype)

    def __repr__(self):
        return f"Box({self.low.min()}, {self.high.max()}, {self.shape}, {self.dtype})"


class _Dict:
    """Named sub-spaces."""

    def __init__(self, spaces: Mapping, seed=None):
        self.spaces = dict(spaces)
        if seed is not None:
            self.seed(seed)

    def seed(self, seed=None):
        seeds = np.random.SeedSequence(seed).spawn(len(self.spaces))
        for space, s in zip(self.spaces.values(), seeds):
            space.seed(int(s.generate_state(1)[0]))
        return [seed]

    def contains(self, x) -> bool:
        return (isinstance(x, Mapping) and set(x) == set(self.spaces)
                and all(self.spaces[k].contains(x[k]) for k in self.spaces))

    def __contains__(self, x) -> bool:
        return self.contains(x)

    def sample(self):
        return {k: s.sample() for k, s in self.spaces.items()}

    def __getitem__(self, key):
        return self.spaces[key]

    def keys(self):
        return self.spaces.keys()

    def __repr__(self):
        return "Dict(" + ", ".join(f"{k}: {v!r}" for k, v in self.spaces.items()) + ")"


Box = _gym_spaces.Box if _gym_spaces else _Box
Dict = _gym_spaces.Dict if _gym_spaces else _Dict
