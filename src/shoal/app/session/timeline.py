"""The timeline of a session: which recorded step is shown, and a loaded replay.

* **Scrub**: a cursor on a recorded step (``cursor``; None shows the live end). The session
  pauses and shows that frame: the robots, the trails up to then and the plots cut there.
* **Replay**: a loaded :class:`~shoal.app.replay.Recording` replaces the history (with the
  scene as it was at each frame, and swarm B's frames when Compare ran); it opens at its first
  step, the engine does not advance and Play and Step move the cursor through the recording
  (Play at its end starts it again; :meth:`Timeline.rewind` goes back to its start).
* :func:`verify_replay` re-simulates the first steps of a recording's preset and seed in a
  fresh session and compares the positions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol, Sequence

import numpy as np

from ..replay import Recording
from .history import Frame, History

VERIFY_STEPS = 20  # steps re-simulated to check a loaded replay
MAX_VERIFY_START = 2000  # a recording that starts later than this step is not re-simulated


@dataclass(frozen=True)
class ReplayInfo:
    """What the badge says about the replay shown."""

    name: str
    seed: int
    shoal: str
    verified: bool | None  # None: not checked
    check: str  # the determinism check, in words
    live_edits: int
    twin: dict[str, Any] | None = None  # swarm B's overrides when it was recorded


class Rerun(Protocol):
    """A fresh session to re-simulate a recording in."""

    history: History

    @property
    def k(self) -> int: ...

    def advance(self, n: int = 1) -> int: ...


def verify_replay(fresh: Rerun, rec: Recording, steps: int = VERIFY_STEPS) -> tuple[bool | None, str]:
    """Run a ``fresh`` session of the embedded preset and seed through the first ``steps``
    recorded steps and compare the robots' positions with the recording."""
    k0 = int(rec.k[0])
    if k0 > MAX_VERIFY_START:
        return None, f"not checked: the recording starts at step {k0}"
    upto = [i for i in range(rec.frames) if rec.k[i] <= k0 + steps]
    fresh.advance(int(rec.k[upto[-1]]) - fresh.k)
    history = fresh.history
    for i in upto:
        x, _, _ = rec.robots(i)
        at = history.index_of(int(rec.k[i]))
        f = history.frames[at] if at is not None else None
        if f is None or f.x.shape != x.shape or not np.allclose(f.x, x, rtol=0.0, atol=1e-9, equal_nan=True):
            gap = float(np.nanmax(np.abs(f.x - x))) if f is not None and f.x.shape == x.shape else float("nan")
            what = f"max gap {gap:.3g}" if np.isfinite(gap) else "other robots"
            return False, (f"not reproduced: step {int(rec.k[i])} differs from a fresh run of the preset and seed "
                           f"({what}); it was probably changed while it ran")
    span = int(rec.k[upto[-1]]) - k0
    return True, f"verified: steps {k0}–{k0 + span} match a fresh run of the preset and seed"


def recorded_frames(rec: Recording) -> list[Frame]:
    """The frames of a recording with the scene as it was (velocities are not recorded: zero)."""
    frames = []
    for i in range(rec.frames):
        x, heading, status = rec.robots(i)
        frames.append(Frame(int(rec.k[i]), float(rec.t[i]), x, np.zeros_like(x), heading, status,
                            scene=rec.scene_at(i)))  # (k, t, x, u, heading, status)
    return frames


def twin_frames(rec: Recording) -> list[Frame]:
    """Swarm B's recorded frames (none without B): robots and status, nothing else."""
    frames = []
    for i in range(rec.frames):
        b = rec.twin(i)
        if b is not None:
            x, status = b
            frames.append(Frame(int(rec.k[i]), float(rec.t[i]), x, np.zeros_like(x), np.zeros(len(x)), status))
    return frames


class Timeline:
    """Cursor (``cursor``: the step shown, None = live) and replay (``replaying``) over a history."""

    def __init__(self, history: History) -> None:
        self.history = history
        self.twin = History(("t",))  # swarm B's frames in the replay shown
        self.clear()

    def clear(self) -> None:
        self.cursor: int | None = None
        self.replaying: ReplayInfo | None = None
        self.twin.clear()

    @property
    def twin_frames(self) -> Sequence[Frame]:
        """Swarm B's frames in the replay shown (none without B)."""
        return self.twin.frames

    @property
    def live(self) -> bool:
        """Is the live end shown (no scrubbed step, no replay)?"""
        return self.cursor is None and self.replaying is None

    def shown_index(self) -> int:
        ks = self.history.ks
        if self.cursor is None:
            return len(ks) - 1
        return min(int(np.searchsorted(ks, self.cursor)), len(ks) - 1)

    def shown_frame(self) -> Frame:
        return self.history.frames[self.shown_index()]

    def span(self) -> tuple[int, int, int]:
        """(first, last, shown) recorded step numbers."""
        ks = self.history.ks
        return int(ks[0]), int(ks[-1]), int(ks[self.shown_index()])

    def scrub(self, k: int) -> int:
        """Put the cursor on the recorded step nearest ``k``; returns that step."""
        ks = self.history.ks
        i = min(int(np.searchsorted(ks, int(k))), len(ks) - 1)
        if i > 0 and abs(ks[i - 1] - k) <= abs(ks[i] - k):
            i -= 1
        self.cursor = int(ks[i])
        return self.cursor

    def advance(self, n: int) -> tuple[int, bool]:
        """Move ``n`` frames on; returns (frames moved, at the end)."""
        ks = self.history.ks
        i = self.shown_index()
        j = min(i + max(n, 0), len(ks) - 1)
        self.cursor = int(ks[j])
        return j - i, j == len(ks) - 1

    def rewind_if_at_end(self) -> bool:
        """A replay at its last frame goes back to its first (Play again); True if it did."""
        ks = self.history.ks
        if len(ks) and self.cursor == ks[-1]:
            self.cursor = int(ks[0])
            return True
        return False

    def rewind(self) -> None:
        """The cursor on the first recorded frame."""
        self.cursor = int(self.history.ks[0])

    def load(self, rec: Recording, check: tuple[bool | None, str], metrics_match: bool) -> None:
        """Show ``rec`` instead of the live history (its metric rows too if their names match)."""
        self.history.replace(recorded_frames(rec), (tuple(float(v) for v in row) for row in rec.metrics)
                             if metrics_match else (), motion=False)
        self.rewind()  # a replay opens at its start: Play plays it from there
        self.twin.replace(twin_frames(rec), (), motion=False)
        self.replaying = ReplayInfo(name=rec.name, seed=rec.seed, shoal=str(rec.meta["shoal"]), verified=check[0],
                                    check=check[1], live_edits=int(rec.meta["live_edits"]),
                                    twin=rec.twin_overrides if len(self.twin_frames) else None)

    def shown_metrics(self, n: int) -> tuple[dict[str, np.ndarray], tuple[float, float]]:
        """The last ``n`` metric rows up to the time shown, and the time span of all ``n`` (the x range)."""
        m = self.history.metric_tail(n)
        t = m["t"]
        span = (float(t[0]), float(t[-1])) if len(t) else (0.0, 1.0)
        if not self.live:
            keep = t <= self.shown_frame().t + 1e-9
            m = {k: v[keep] for k, v in m.items()}
        return m, span

    def metadata(self) -> dict[str, Any]:
        """Version and live edits of the replay shown (empty when live)."""
        if self.replaying is None:
            return {}
        return {"shoal": self.replaying.shoal, "live_edits": self.replaying.live_edits}
