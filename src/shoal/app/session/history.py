"""The recorded history of a session: the robots of run 0 step by step (a bounded ring
buffer) and one metric row per step; trails and the trajectory export read from it."""

from __future__ import annotations

import bisect
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping

import numpy as np

from shoal.engine.core.recorder import TRAJECTORY_COLUMNS

from ..replay import MAX_ROWS  # a replay holds what a history keeps

TRAIL_LIMITS = (80, 40)  # at most this many trails of this many points


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
    """Run 0 of an engine ``state`` (``x``, ``u``, ``heading``, ``status``, ``k``; ``a`` if asked)."""
    return Frame(k=state.k, t=t, x=state.x[0].copy(), u=state.u[0].copy(), heading=state.heading[0].copy(),
                 status=state.status[0].copy(), a=state.a[0].copy() if accelerations else None, scene=scene or {})


def trail_array(frames: list[Frame], t_now: float, horizon: float, max_trails: int, max_points: int) -> np.ndarray:
    """(M, L, d) positions of the last ``horizon`` seconds, oldest first, M ≤ ``max_trails``.

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


def robots_at(frames: list[Frame], k: int, horizon: float) -> tuple[np.ndarray, np.ndarray] | None:
    """The robots at step ``k`` of ``frames`` and their trails of the last ``horizon`` seconds
    (None if no frame has step ``k``): how swarm B is drawn beside A."""
    i = bisect.bisect_left(frames, k, key=lambda f: f.k)  # (no list of steps per draw)
    if i == len(frames) or frames[i].k != k:
        return None
    f = frames[i]
    return f.x.copy(), trail_array(frames[: i + 1], f.t, horizon, *TRAIL_LIMITS)


def frame_rows(frames: list[Frame]) -> np.ndarray:
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


class History:
    """Frames and metric rows (columns ``names``) of one session, oldest first.

    At most ``max_steps`` frames and ``max_rows`` (step, robot) rows are kept, and at most
    ``max_metrics`` metric rows: a tab left playing for hours holds a constant amount of memory.
    """

    def __init__(self, names: tuple[str, ...], max_steps: int = 5000, max_rows: int = MAX_ROWS,
                 max_metrics: int = 5000) -> None:
        self.names = names
        self.max_steps, self.max_rows, self.max_metrics = max_steps, max_rows, max_metrics
        self.clear()

    def clear(self) -> None:
        """Forget everything (a new deque: callers can tell a cleared history by identity)."""
        self.frames: deque[Frame] = deque()
        self.metrics: deque[tuple[float, ...]] = deque()
        self._rows = 0

    def record(self, frame: Frame, row: tuple[float, ...]) -> None:
        self.frames.append(frame)
        self._rows += frame.x.shape[0]
        while len(self.frames) > 1 and (len(self.frames) > self.max_steps or self._rows > self.max_rows):
            self._rows -= self.frames.popleft().x.shape[0]
        self.metrics.append(row)
        while len(self.metrics) > self.max_metrics:
            self.metrics.popleft()

    def replace(self, frames: Iterable[Frame], rows: Iterable[tuple[float, ...]]) -> None:
        """Show a recording instead: its frames and metric rows, all of them."""
        self.clear()
        self.frames.extend(frames)
        self._rows = sum(f.x.shape[0] for f in self.frames)
        self.metrics.extend(rows)

    def steps(self) -> list[int]:
        return [f.k for f in self.frames]

    def metric_table(self) -> np.ndarray:
        """(M, len(names)) metric rows."""
        return np.array(self.metrics, dtype=float).reshape(-1, len(self.names))

    def metric_arrays(self) -> dict[str, np.ndarray]:
        """The recorded metrics as columns named by ``names``."""
        m = self.metric_table()
        return {name: m[:, j] for j, name in enumerate(self.names)}

    def trails(self, t_now: float, horizon: float, max_trails: int, max_points: int,
               upto: int | None = None) -> np.ndarray:
        """(M, L, d) trails of the last ``horizon`` seconds before ``t_now``, ending at frame ``upto``
        (default: the newest)."""
        frames = list(self.frames)
        if upto is not None:
            frames = frames[: upto + 1]
        return trail_array(frames, t_now, horizon, max_trails, max_points)

    def rows(self) -> np.ndarray:
        """Trajectory rows of every frame kept (see :func:`frame_rows`)."""
        return frame_rows(list(self.frames))
