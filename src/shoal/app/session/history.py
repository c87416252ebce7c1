"""The recorded history of a session: the robots of run 0 step by step and one metric row per
step, in preallocated rings (:mod:`.ring`) sized by a memory budget; trails, the plots, the
timeline and the exports read from it.

Every read a tick makes is a slice or an index into the rings (the trails of the last seconds,
the last metric rows, the frame of a step): its work depends on the horizon or the plot's window,
never on how long the run has gone on.

**The budget.** A history holds at most :data:`HISTORY_BUDGET` numbers (a float or an integer
each): the frames' slots (positions, velocities, accelerations for Chapter 3, heading, status),
the metric rows and the scene parts that changed while the run went on. It counts numbers, not
rows: 2,000 robots in 1,000 dimensions fill it with a frame or two, 20 robots in the plane keep
their 5,000 steps. A run that reaches it goes on with a shorter history (the oldest steps go
first) and ``shortened`` says so for the status line.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping

import numpy as np

from shoal.engine.core.recorder import TRAJECTORY_COLUMNS

from ..replay import MAX_ROWS  # a replay holds what a history keeps
from .ring import FrameRing, FrameView, MetricRing

TRAIL_LIMITS = (80, 40)  # at most this many trails of this many points
TRAIL_DIMS = 3  # coordinates a trail keeps (the arena draws the first two)
HISTORY_BUDGET = 4 * 2**20  # numbers (32 MiB of float64) a tab's history holds at most (A's and B's together)
METRIC_SHARE = 8  # at most 1/8 of the budget for metric rows …
SCENE_SHARE = 8  # … and 1/8 for the scene parts that changed while the run went on


@dataclass(frozen=True)
class Frame:
    """The robots (run 0) after step ``k``: what trails and export need (``a`` only for Ch. 3), and
    the parts of the scene that may change while the run goes on (``scene``: a fleet's obstacles,
    a sonar's source; see ``replay.scene_parts``), as the arena drew them then. An unchanged part
    is the same array from frame to frame: never written to, it costs nothing per frame."""

    k: int
    t: float
    x: np.ndarray  # (N, d)
    u: np.ndarray  # (N, d)
    heading: np.ndarray  # (N,)
    status: np.ndarray  # (N,)
    a: np.ndarray | None = None  # (N, d)
    scene: Mapping[str, np.ndarray] = field(default_factory=dict)


def frame_of(state: Any, t: float, *, accelerations: bool = False, scene: Mapping[str, np.ndarray] | None = None
             ) -> Frame:
    """Run 0 of an engine ``state`` (``x``, ``u``, ``heading``, ``status``, ``k``; ``a`` if asked), as
    views of its arrays: :meth:`History.record` copies them into its rings at once."""
    return Frame(k=state.k, t=t, x=state.x[0], u=state.u[0], heading=state.heading[0], status=state.status[0],
                 a=state.a[0] if accelerations else None, scene=scene or {})


_EPOCHS = itertools.count(1_000_000_000)  # epochs of trails made from plain arrays: never a history's


@dataclass(frozen=True)
class Trails:
    """Trails of the last ``view.trail_seconds``: ``points`` (M, L, dims), oldest first, M ≤ the
    robots. Column ``j`` is the robots at step ``steps[j]``: every ``stride``-th step of the window
    (by step number, so the points stay put from frame to frame), then the frame they end at.
    ``epoch`` names the history they come from: within one epoch a step's points never change,
    so a view can keep what it drew of them (see :mod:`shoal.app.view.trails`)."""

    points: np.ndarray
    steps: np.ndarray
    stride: int = 1
    epoch: int = -1

    @classmethod
    def of(cls, points: np.ndarray) -> Trails:
        """Trails from a plain (M, L, d) array (each such is drawn afresh)."""
        p = np.asarray(points, dtype=float)
        return cls(p, np.arange(p.shape[1] if p.ndim == 3 else 0), 1, next(_EPOCHS))

    @classmethod
    def empty(cls, dims: int = 2) -> Trails:
        return cls(np.zeros((0, 0, dims)), np.zeros(0, np.int64))

    def __len__(self) -> int:
        return int(self.points.shape[0])

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(self.points.shape)


def trail_array(frames: list[Frame], t_now: float, horizon: float, max_trails: int, max_points: int) -> np.ndarray:
    """(M, L, d) positions of the last ``horizon`` seconds, oldest first, M ≤ ``max_trails``: the
    list-of-frames reference that :meth:`History.trails` gives the same points as.

    At most ``max_points`` per trail: every stride-th step by step number (not by position in
    the window), so the kept points stay put from frame to frame instead of shimmering.
    """
    recent = [f for f in frames if f.t >= t_now - horizon - 1e-9]
    if len(recent) > max_points:
        stride = -(-len(recent) // (max_points - 1))
        recent = [f for f in recent[:-1] if f.k % stride == 0] + recent[-1:]
    if len(recent) < 2:
        d = frames[-1].x.shape[-1] if frames else 2
        return np.zeros((0, 0, d))
    m = min(min(f.x.shape[0] for f in recent), max_trails)
    return np.stack([f.x[:m] for f in recent], axis=1)


def frame_rows(frames: Iterable[Frame]) -> np.ndarray:
    """Rows ``run,step,t,robot,x,y,heading,vx,vy,status`` (run 0) of ``frames``."""
    blocks = []
    for f in frames:
        n, d = f.x.shape
        comp = lambda a, j, n=n, d=d: a[:, j] if d > j else np.zeros(n)  # noqa: E731
        blocks.append(np.column_stack([
            np.zeros(n), np.full(n, f.k), np.full(n, f.t), np.arange(n),
            comp(f.x, 0), comp(f.x, 1), f.heading, comp(f.u, 0), comp(f.u, 1), f.status,
        ]))
    return np.vstack(blocks) + 0.0 if blocks else np.zeros((0, len(TRAJECTORY_COLUMNS)))


def _make_frame(k: int, t: float, x: np.ndarray, u: np.ndarray, heading: np.ndarray, status: np.ndarray,
                a: np.ndarray | None, scene: Mapping[str, np.ndarray]) -> Frame:
    return Frame(k, t, x, u, heading, status, a, scene)


def _scene_numbers(scene: Mapping[str, np.ndarray], other: Mapping[str, np.ndarray]) -> int:
    """Numbers of the parts of ``scene`` that are not the same arrays as in ``other``."""
    return sum(int(np.size(v)) for part, v in scene.items() if other.get(part) is not v)


class History:
    """Frames and metric rows (columns ``names``) of one session, oldest first.

    At most ``max_steps`` frames, ``max_rows`` (step, robot) rows and ``max_metrics`` metric rows,
    and at most ``budget`` numbers in all: a tab left playing for hours holds a constant amount of
    memory, and a scene of many robots in many dimensions a shorter history.
    """

    def __init__(self, names: tuple[str, ...], max_steps: int = 5000, max_rows: int = MAX_ROWS,
                 max_metrics: int = 5000, budget: int = HISTORY_BUDGET) -> None:
        self.names = names
        self._ring = FrameRing()
        self._metrics = MetricRing()
        self._max_steps, self._max_rows, self._max_metrics, self._budget = max_steps, max_rows, max_metrics, budget
        self._replaced: tuple[int, int] | None = None  # (frames, rows) of a recording shown: all of them kept
        self._scene_total = 0  # numbers of the scene parts the frames hold (each changed part once)
        self._stale = True
        self.cut = False
        self.frames = FrameView(self._ring, _make_frame)
        self.clear()

    # ------------------------------------------------------------------ limits
    @property
    def max_steps(self) -> int:
        return self._max_steps

    @max_steps.setter
    def max_steps(self, value: int) -> None:
        self._max_steps = int(value)
        self._stale = True

    @property
    def max_rows(self) -> int:
        return self._max_rows

    @max_rows.setter
    def max_rows(self, value: int) -> None:
        self._max_rows = int(value)
        self._stale = True

    @property
    def max_metrics(self) -> int:
        return self._max_metrics

    @max_metrics.setter
    def max_metrics(self, value: int) -> None:
        self._max_metrics = int(value)
        self._stale = True

    @property
    def budget(self) -> int:
        """Numbers this history may hold."""
        return self._budget

    @budget.setter
    def budget(self, value: int) -> None:
        self._budget = max(int(value), 1)
        self._stale = True

    def _metric_capacity(self, columns: int) -> int:
        want = self._replaced[1] if self._replaced is not None else self._max_metrics
        return max(1, min(want, self._budget // METRIC_SHARE // max(2 * columns, 1)))

    def _frame_capacity(self, width: int, d: int, with_u: bool, with_a: bool) -> int:
        per = FrameRing.numbers_per_frame(width, d, with_u, with_a) + 1
        room = self._budget - self._budget // SCENE_SHARE - self._metric_capacity(len(self.names)) * 2 * len(self.names)
        want = self._replaced[0] if self._replaced is not None else min(self._max_steps,
                                                                           self._max_rows // max(width, 1))
        return max(1, min(want, room // per))

    def _fit(self, width: int | None = None, d: int | None = None, with_u: bool | None = None,
             with_a: bool | None = None) -> None:
        """Size the rings for frames of ``width`` robots in ``d`` dimensions (default: as they are)."""
        self._stale = False
        r = self._ring
        width = r.width if width is None else width
        d = r.d if d is None else d
        with_u = r.with_u if with_u is None else with_u
        with_a = r.with_a if with_a is None else with_a
        capacity = self._frame_capacity(max(width, 1), max(d, 1), with_u, with_a)
        if capacity < len(r) and capacity < self._wanted():
            self.cut = True
        r.resize(capacity)
        self._metrics.resize(self._metric_capacity(len(self.names)))
        self._scene_total = min(self._scene_total, self._scene_room())

    def _scene_room(self) -> int:
        return self._budget // SCENE_SHARE

    # ------------------------------------------------------------------ writing
    def clear(self) -> None:
        """Forget everything (and start a new ``epoch``: what was drawn of the old frames is stale)."""
        self._ring.clear()
        self._metrics.clear()
        self._replaced = None
        self._scene_total = 0
        self._stale = True  # the rings are sized again at the next frame
        self.cut = False  # the budget (or the row cap) made the history shorter than ``max_steps``

    @property
    def epoch(self) -> int:
        """Changes whenever the history is cleared or replaced."""
        return self._ring.epoch

    @property
    def metrics(self) -> MetricRing:
        """The metric rows (``len``; iterating gives tuples)."""
        return self._metrics

    def record(self, frame: Frame, row: tuple[float, ...]) -> None:
        self._append(frame, motion=True)
        self._metrics.append(row)

    def _append(self, frame: Frame, *, motion: bool) -> None:
        r = self._ring
        n, d = frame.x.shape
        with_a = frame.a is not None
        if self._stale or not r.capacity or n > r.width or d != r.d or motion != r.with_u or with_a != r.with_a:
            self._fit(max(n, r.width if d == r.d else 0), d, motion, with_a)
        if r.capacity and len(r) == r.capacity and r.capacity < self._wanted():
            self.cut = True
        newest = r.scene[r.slots(len(r) - 1)] if len(r) else {}
        self._scene_total += _scene_numbers(frame.scene, newest)
        dropped = r.append(frame.k, frame.t, frame.x, frame.u if motion else None, frame.heading, frame.status,
                           frame.a, frame.scene)
        if dropped:
            self._scene_total -= _scene_numbers(dropped, r.scene[r.head] if len(r) else {})
        while self._scene_total > self._scene_room() and len(r) > 1:
            gone = r.drop_oldest()
            self._scene_total -= _scene_numbers(gone, r.scene[r.head])
            self.cut = True

    def _wanted(self) -> int:
        return self._replaced[0] if self._replaced is not None else self._max_steps

    def replace(self, frames: Iterable[Frame], rows: Iterable[tuple[float, ...]], *, motion: bool = True) -> None:
        """Show a recording instead: its frames and metric rows, all of them that the budget holds
        (``motion`` False: its frames carry no velocities, none are stored)."""
        frames, rows = list(frames), list(rows)
        self.clear()
        self._replaced = (max(len(frames), 1), max(len(rows), 1))
        for f in frames:
            self._append(f, motion=motion)
        for row in rows:
            self._metrics.append(row)

    # ------------------------------------------------------------------ reading
    @property
    def ks(self) -> np.ndarray:
        """Step numbers of the frames, oldest first (a view: read it under the session's lock)."""
        return self._ring.ks

    @property
    def ts(self) -> np.ndarray:
        """Times of the frames, oldest first (a view)."""
        return self._ring.ts

    def steps(self) -> np.ndarray:
        return self._ring.ks.copy()

    def index_of(self, k: int) -> int | None:
        """The index of the frame of step ``k`` (None if there is none)."""
        ks = self._ring.ks
        i = int(np.searchsorted(ks, k))
        return i if i < len(ks) and ks[i] == k else None

    @property
    def shortened(self) -> str | None:
        """Why the history keeps fewer steps than ``max_steps`` (None while it does not)."""
        if not self.cut:
            return None
        return (f"the history keeps the last {len(self._ring):,} steps (the tab's memory budget of "
                f"{self._budget * 8 / 2**20:.0f} MiB)")

    def allocated(self) -> int:
        """Numbers allocated for this history's rings, scene parts counted."""
        return self._ring.allocated + self._metrics.allocated + self._scene_total

    def metric_table(self) -> np.ndarray:
        """(M, len(names)) metric rows (a copy)."""
        return self._metrics.tail(len(self._metrics)).copy().reshape(-1, len(self.names))

    def metric_arrays(self) -> dict[str, np.ndarray]:
        """The recorded metrics as columns named by ``names``."""
        return self.metric_tail(len(self._metrics))

    def metric_tail(self, n: int) -> dict[str, np.ndarray]:
        """The last ``n`` metric rows as columns named by ``names`` (copies)."""
        m = self._metrics.tail(n)
        if m.shape[1] != len(self.names):
            return {name: np.zeros(0) for name in self.names}
        return {name: m[:, j].copy() for j, name in enumerate(self.names)}

    def metric_around(self, t0: float) -> dict[str, np.ndarray]:
        """The metric rows from the last one before time ``t0`` on (what interpolates at times ≥ ``t0``)."""
        m = self._metrics.tail(len(self._metrics))
        if m.shape[1] != len(self.names) or "t" not in self.names:
            return {name: np.zeros(0) for name in self.names}
        j = self.names.index("t")
        first = max(int(np.searchsorted(m[:, j], t0)) - 1, 0)
        return {name: m[first:, c].copy() for c, name in enumerate(self.names)}

    def trails(self, t_now: float, horizon: float, max_trails: int, max_points: int,
               upto: int | None = None) -> Trails:
        """Trails of the last ``horizon`` seconds before ``t_now``, ending at frame ``upto``
        (default: the newest): the points of :func:`trail_array` (first :data:`TRAIL_DIMS`
        coordinates), found by bisection and an index into the ring."""
        r = self._ring
        last = len(r) - 1 if upto is None else min(int(upto), len(r) - 1)
        dims = min(r.d, TRAIL_DIMS) if r.d else 2
        if last < 1:
            return Trails(np.zeros((0, 0, dims)), np.zeros(0, np.int64), 1, r.epoch)
        ts, ks = r.ts[: last + 1], r.ks[: last + 1]
        first = int(np.searchsorted(ts, t_now - horizon - 1e-9, side="left"))
        n = last + 1 - first
        stride = 1
        if n > max_points:
            stride = -(-n // (max_points - 1))
            cols = np.append(first + np.flatnonzero(ks[first:last] % stride == 0), last)
        else:
            cols = np.arange(first, last + 1)
        if len(cols) < 2:
            return Trails(np.zeros((0, 0, dims)), np.zeros(0, np.int64), stride, r.epoch)
        m = int(min(r.counts(cols).min(), max_trails))
        return Trails(r.positions(cols, m, dims), ks[cols].copy(), stride, r.epoch)

    def robots_at(self, k: int, horizon: float) -> tuple[np.ndarray, Trails] | None:
        """The robots at step ``k`` and their trails of the last ``horizon`` seconds (None if no
        frame has step ``k``): how swarm B is drawn beside A."""
        i = self.index_of(k)
        if i is None:
            return None
        f = self.frames[i]
        return f.x, self.trails(f.t, horizon, *TRAIL_LIMITS, upto=i)

    def motion(self, name: str, robot: int, dim: int, n: int) -> np.ndarray:
        """The last ``n`` values of ``u`` or ``a`` of one robot and coordinate (empty where they are
        not recorded or the robot did not exist then)."""
        r = self._ring
        if not r.has(name) or not len(r) or dim >= r.d or robot >= r.width:
            return np.zeros(0)
        frames = np.arange(max(len(r) - n, 0), len(r))
        frames = frames[r.counts(frames) > robot]
        return r.column(name, frames, robot, dim)

    def positions_after(self, k: int, dims: int = 2) -> tuple[np.ndarray, np.ndarray]:
        """The steps after step ``k`` and the robots' positions at each, (F, N, ``dims``), NaN for
        robots a frame did not have: what a reader that keeps its own per-step values needs anew."""
        r = self._ring
        if not len(r):
            return np.zeros(0, np.int64), np.zeros((0, 0, dims))
        first = int(np.searchsorted(r.ks, k, side="right"))
        frames = np.arange(first, len(r))
        x = r.positions(frames, r.width, min(dims, r.d)).transpose(1, 0, 2).copy()
        x[np.arange(r.width)[None, :] >= r.counts(frames)[:, None]] = np.nan
        return r.ks[first:].copy(), x

    def rows(self) -> np.ndarray:
        """Trajectory rows of every frame kept (see :func:`frame_rows`)."""
        return frame_rows(self.frames)


def robots_at(frames: list[Frame], k: int, horizon: float) -> tuple[np.ndarray, np.ndarray] | None:
    """The robots at step ``k`` of a list of ``frames`` and their trail array (the list reference
    of :meth:`History.robots_at`)."""
    at = [i for i, f in enumerate(frames) if f.k == k]
    if not at:
        return None
    f = frames[at[0]]
    return f.x.copy(), trail_array(frames[: at[0] + 1], f.t, horizon, *TRAIL_LIMITS)
