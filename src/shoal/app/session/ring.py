"""Preallocated ring buffers of a session's history: robot frames and metric rows.

A :class:`FrameRing` keeps the robots of run 0 step by step in arrays allocated once for its
capacity (``x``, ``u``, ``heading``, ``status``, ``a``: one slot a frame, as wide as the most
robots seen), so recording a step writes one slot and reading the frames of a window is an
index into them: nothing is rebuilt from a list of frames on a tick. Step numbers and times are
also written a second time one capacity further on (a mirrored ring), so every run of
consecutive frames is one contiguous slice (``ks``, ``ts``) that a search can bisect.

A :class:`MetricRing` does the same for the metric rows (mirrored too: the last ``n`` rows are
one view).

Neither knows about budgets or scenes' meaning: :class:`~.history.History` sizes them.
"""

from __future__ import annotations

from typing import Any, Iterator, Mapping, Sequence, overload

import numpy as np


class FrameRing:
    """Frames oldest first; logical frame ``i`` is slot ``(head + i) % capacity``.

    Frames may have fewer robots than the widest one (``sim.robots`` changed while the run went
    on): each slot records its own count ``n``. A frame wider than the slots, or of another
    dimension, reallocates them (a user's change, never a tick's work); the frames that no longer
    fit are dropped, oldest first.
    """

    def __init__(self, capacity: int = 1) -> None:
        self._want = max(int(capacity), 1)
        self.capacity = 0
        self.width = 0  # robots a slot holds
        self.d = 0
        self.with_u = self.with_a = False
        self.head = self.size = 0
        self.epoch = 0  # bumps when the frames are forgotten (a trail drawn from older ones is stale)
        self._arrays: dict[str, np.ndarray] = {}
        self.scene: list[Mapping[str, np.ndarray]] = []

    # ------------------------------------------------------------------ shape
    @staticmethod
    def numbers_per_frame(width: int, d: int, with_u: bool = True, with_a: bool = False) -> int:
        """Numbers one slot holds: positions (and velocities, accelerations), heading, status, step, time, count."""
        return width * (d * (1 + int(with_u) + int(with_a)) + 2) + 3

    @property
    def per_frame(self) -> int:
        return self.numbers_per_frame(self.width, self.d, self.with_u, self.with_a)

    @property
    def allocated(self) -> int:
        """Numbers held by the slots (allocated, whether written yet or not)."""
        return self.capacity * self.per_frame + self.capacity  # (+ the mirrored step and time)

    def resize(self, capacity: int) -> None:
        """At most ``capacity`` frames from now on (the oldest go if there are more)."""
        self._want = max(int(capacity), 1)
        if self.capacity and self._want != self.capacity:
            self._allocate(self.width, self.d, self.with_u, self.with_a)

    def _allocate(self, width: int, d: int, with_u: bool, with_a: bool, status_dtype: Any = np.int8) -> None:
        """(Re)allocate the slots for ``width`` robots in ``d`` dimensions, keeping the newest
        frames that fit and have that dimension."""
        keep = self.size if d == self.d and self._arrays else 0
        keep = min(keep, self._want)
        old = {name: self._ordered(name, keep) for name in self._arrays} if keep else {}
        old_scene = [self.scene[(self.head + i) % self.capacity] for i in range(self.size - keep, self.size)]
        c = self._want
        dtype = old["status"].dtype if "status" in old else status_dtype
        self._arrays = {
            "k": np.zeros(2 * c, np.int64), "t": np.zeros(2 * c, np.float64), "n": np.zeros(c, np.int64),
            "x": np.zeros((c, width, d)), "heading": np.zeros((c, width)), "status": np.zeros((c, width), dtype),
        }
        if with_u:
            self._arrays["u"] = np.zeros((c, width, d))
        if with_a:
            self._arrays["a"] = np.zeros((c, width, d))
        self.capacity, self.width, self.d, self.with_u, self.with_a = c, width, d, with_u, with_a
        self.scene = [{}] * c
        self.head, self.size = 0, keep
        for name, values in old.items():
            if name not in self._arrays:
                continue
            a = self._arrays[name]
            if name in ("k", "t"):
                a[:keep] = a[c:c + keep] = values
            elif name == "n":
                a[:keep] = values
            else:
                a[:keep, : values.shape[1]] = values[:, : a.shape[1]]
        self.scene[:keep] = old_scene

    def _ordered(self, name: str, count: int) -> np.ndarray:
        """The last ``count`` frames' values of array ``name``, oldest first (a copy)."""
        slots = self.slots(np.arange(self.size - count, self.size))
        return self._arrays[name][slots].copy()

    # ------------------------------------------------------------------ writing
    def clear(self) -> None:
        """Forget every frame (the slots stay allocated)."""
        self.head = self.size = 0
        self.scene = [{}] * self.capacity
        self.epoch += 1

    def append(self, k: int, t: float, x: np.ndarray, u: np.ndarray | None, heading: np.ndarray,
               status: np.ndarray, a: np.ndarray | None, scene: Mapping[str, np.ndarray]) -> Mapping[str, np.ndarray]:
        """Write one frame into the next slot (the oldest frame goes when the ring is full); returns
        the scene of the frame it dropped ({} if none)."""
        n, d = x.shape
        with_u, with_a = u is not None, a is not None
        if not self.capacity or n > self.width or d != self.d or with_u != self.with_u or with_a != self.with_a:
            self._allocate(max(n, self.width if d == self.d else 0), d, with_u, with_a, status.dtype)
        dropped: Mapping[str, np.ndarray] = {}
        if self.size == self.capacity:
            dropped = self.scene[self.head]
            self.head = (self.head + 1) % self.capacity
            self.size -= 1
        p = (self.head + self.size) % self.capacity
        arr = self._arrays
        arr["k"][p] = arr["k"][p + self.capacity] = k
        arr["t"][p] = arr["t"][p + self.capacity] = t
        arr["n"][p] = n
        arr["x"][p, :n] = x
        arr["heading"][p, :n] = heading
        arr["status"][p, :n] = status
        if "u" in arr:
            arr["u"][p, :n] = u if u is not None else 0.0
        if "a" in arr:
            arr["a"][p, :n] = a if a is not None else 0.0
        self.scene[p] = scene
        self.size += 1
        return dropped

    def drop_oldest(self) -> Mapping[str, np.ndarray]:
        """Forget the oldest frame; returns its scene."""
        dropped = self.scene[self.head]
        self.scene[self.head] = {}
        self.head = (self.head + 1) % self.capacity
        self.size -= 1
        return dropped

    # ------------------------------------------------------------------ reading
    def __len__(self) -> int:
        return self.size

    def slots(self, i: np.ndarray | int) -> Any:
        """The slots of logical frames ``i``."""
        return (self.head + i) % max(self.capacity, 1)

    @property
    def ks(self) -> np.ndarray:
        """Step numbers, oldest first (a view: valid until the next write)."""
        return self._arrays["k"][self.head:self.head + self.size] if self.size else np.zeros(0, np.int64)

    @property
    def ts(self) -> np.ndarray:
        """Times, oldest first (a view)."""
        return self._arrays["t"][self.head:self.head + self.size] if self.size else np.zeros(0)

    def counts(self, frames: np.ndarray) -> np.ndarray:
        """Robots of logical ``frames`` (a copy)."""
        return self._arrays["n"][self.slots(frames)] if self.size else np.zeros(0, np.int64)

    def positions(self, frames: np.ndarray, robots: int, dims: int) -> np.ndarray:
        """(robots, len(frames), dims) positions of logical ``frames`` (a copy)."""
        return np.ascontiguousarray(self._arrays["x"][self.slots(frames), :robots, :dims].transpose(1, 0, 2))

    def column(self, name: str, frames: np.ndarray, robot: int, dim: int) -> np.ndarray:
        """``name`` (``u``, ``a``) of one robot and dimension over logical ``frames`` (a copy)."""
        return self._arrays[name][self.slots(frames), robot, dim].copy()

    def has(self, name: str) -> bool:
        return name in self._arrays

    def frame(self, i: int) -> tuple[int, float, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None,
                                     Mapping[str, np.ndarray]]:
        """(k, t, x, u, heading, status, a, scene) of logical frame ``i`` (copies of the arrays)."""
        if not -self.size <= i < self.size:
            raise IndexError(f"frame {i} of {self.size}")
        p = self.slots(i % self.size)
        arr = self._arrays
        n = int(arr["n"][p])
        x = arr["x"][p, :n].copy()
        u = arr["u"][p, :n].copy() if "u" in arr else np.zeros_like(x)
        a = arr["a"][p, :n].copy() if "a" in arr else None
        return (int(arr["k"][p]), float(arr["t"][p]), x, u, arr["heading"][p, :n].copy(), arr["status"][p, :n].copy(),
                a, self.scene[p])


class MetricRing:
    """Metric rows (``columns`` numbers each), oldest first, in one mirrored array."""

    def __init__(self, capacity: int = 1) -> None:
        self._want = max(int(capacity), 1)
        self.capacity = self.columns = self.head = self.size = 0
        self._rows = np.zeros((0, 0))

    @property
    def allocated(self) -> int:
        return int(self._rows.size)

    def resize(self, capacity: int) -> None:
        self._want = max(int(capacity), 1)
        if self.capacity and self._want != self.capacity:
            self._allocate(self.columns)

    def _allocate(self, columns: int) -> None:
        keep = min(self.size, self._want) if columns == self.columns else 0
        old = self.tail(keep).copy()
        c = self._want
        self._rows = np.zeros((2 * c, columns))
        self.capacity, self.columns, self.head, self.size = c, columns, 0, keep
        if keep:
            self._rows[:keep] = self._rows[c:c + keep] = old

    def clear(self) -> None:
        self.head = self.size = 0

    def append(self, row: Sequence[float]) -> None:
        if not self.capacity or len(row) != self.columns:
            self._allocate(len(row))
        if self.size == self.capacity:
            self.head = (self.head + 1) % self.capacity
            self.size -= 1
        p = (self.head + self.size) % self.capacity
        self._rows[p] = self._rows[p + self.capacity] = row
        self.size += 1

    def __len__(self) -> int:
        return self.size

    def __iter__(self) -> Iterator[tuple[float, ...]]:
        return (tuple(float(v) for v in row) for row in self.tail(self.size))

    def __getitem__(self, i: int) -> tuple[float, ...]:
        """Row ``i`` (negative from the newest) as a tuple."""
        if not -self.size <= i < self.size:
            raise IndexError(f"row {i} of {self.size}")
        return tuple(float(v) for v in self._rows[self.head + i % self.size])

    def tail(self, n: int) -> np.ndarray:
        """The last ``n`` rows, oldest first (a view: valid until the next write)."""
        n = max(0, min(int(n), self.size))
        end = self.head + self.size
        return self._rows[end - n:end] if n else np.zeros((0, self.columns))

    def since(self, first: int) -> np.ndarray:
        """Rows ``first`` … the last (a view)."""
        return self.tail(self.size - max(int(first), 0))


class FrameView(Sequence[Any]):
    """A :class:`FrameRing` as a sequence of :class:`~.history.Frame` (each built on demand, with
    copies of its arrays: a kept frame is never overwritten by later steps)."""

    def __init__(self, ring: FrameRing, make: Any) -> None:
        self.ring, self._make = ring, make

    def __len__(self) -> int:
        return self.ring.size

    @overload
    def __getitem__(self, i: int) -> Any: ...

    @overload
    def __getitem__(self, i: slice) -> list[Any]: ...

    def __getitem__(self, i: int | slice) -> Any:
        if isinstance(i, slice):
            return [self._make(*self.ring.frame(j)) for j in range(*i.indices(self.ring.size))]
        return self._make(*self.ring.frame(int(i)))

    def __iter__(self) -> Iterator[Any]:
        return (self._make(*self.ring.frame(j)) for j in range(self.ring.size))
