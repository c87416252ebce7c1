"""The timeline of a session: scrubbing through the recorded history, and showing a replay.

* **Scrub**: ``scrub(k)`` pauses and shows the recorded frame of step ``k``: the robots, the
  trails up to then and the plots cut there (``shown_snapshot``, ``shown_metrics``). Play or
  Step carry on from the live end.
* **Replay**: ``enter_replay`` shows a loaded :class:`~shoal.app.replay.Recording` in a
  session built from the preset embedded in it. The engine does not advance: Play and Step
  move through the recording; Reset, or any change that is not only a view setting, leaves
  the replay for a live run of that preset.
* ``recording()`` packs the history into a :class:`Recording`; :func:`verify_replay`
  re-simulates the first steps of the embedded preset and seed and compares the positions.

:class:`TimelineMixin` is part of :class:`~shoal.app.base_session.BaseSession`.
"""

from __future__ import annotations

import bisect
import dataclasses
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

import shoal

from . import replay
from .replay import Recording

VERIFY_STEPS = 20  # steps re-simulated to check a loaded replay
MAX_VERIFY_START = 2000  # a recording that starts later than this step is not re-simulated
TRAIL_LIMITS = (80, 40)  # at most this many trails of this many points (as the live view)


@dataclass(frozen=True)
class ReplayInfo:
    """What the badge says about the replay shown."""

    name: str
    seed: int
    shoal: str
    verified: bool | None  # None: not checked
    check: str  # the determinism check, in words
    live_edits: int


def verify_replay(fresh: Any, rec: Recording, steps: int = VERIFY_STEPS) -> tuple[bool | None, str]:
    """Run a ``fresh`` session of the embedded preset and seed through the first ``steps``
    recorded steps and compare the robots' positions with the recording."""
    k0 = int(rec.k[0])
    if k0 > MAX_VERIFY_START:
        return None, f"not checked: the recording starts at step {k0}"
    upto = [i for i in range(rec.frames) if rec.k[i] <= k0 + steps]
    fresh.step(int(rec.k[upto[-1]]) - fresh.sim.state.k)
    frames = {f.k: f for f in fresh.frames}
    for i in upto:
        x, _, _ = rec.robots(i)
        f = frames.get(int(rec.k[i]))
        if f is None or f.x.shape != x.shape or not np.allclose(f.x, x, rtol=0.0, atol=1e-9, equal_nan=True):
            gap = float(np.nanmax(np.abs(f.x - x))) if f is not None and f.x.shape == x.shape else float("nan")
            what = f"max gap {gap:.3g}" if np.isfinite(gap) else "other robots"
            return False, (f"not reproduced: step {int(rec.k[i])} differs from a fresh run of the preset and seed "
                           f"({what}); it was probably changed while it ran")
    span = int(rec.k[upto[-1]]) - k0
    return True, f"verified: steps {k0}–{k0 + span} match a fresh run of the preset and seed"


class TimelineMixin:
    """Cursor (``cursor``: the step shown, None = live) and replay mode (``replaying``)."""

    cursor: int | None
    replaying: ReplayInfo | None

    # ------------------------------------------------------------------ cursor
    def _steps(self: Any) -> list[int]:
        return [f.k for f in self.frames]

    def _shown_index(self: Any) -> int:
        if self.cursor is None:
            return len(self.frames) - 1
        ks = self._steps()
        return min(bisect.bisect_left(ks, self.cursor), len(ks) - 1)

    def timeline(self: Any) -> tuple[int, int, int]:
        """(first, last, shown) recorded step numbers."""
        with self.lock:
            return self.frames[0].k, self.frames[-1].k, self.frames[self._shown_index()].k

    def scrub(self: Any, k: int) -> int:
        """Pause and show the recorded frame nearest step ``k``; returns its step."""
        with self.lock:
            self.playing = False
            ks = self._steps()
            i = min(bisect.bisect_left(ks, int(k)), len(ks) - 1)
            if i > 0 and abs(ks[i - 1] - k) <= abs(ks[i] - k):
                i -= 1
            self.cursor = ks[i]
            self.revision += 1
            return self.cursor

    def _advance_cursor(self: Any, n: int) -> int:
        """Replay mode: move ``n`` frames on (pauses at the end); returns the frames moved."""
        i = self._shown_index()
        j = min(i + max(n, 0), len(self.frames) - 1)
        self.cursor = self.frames[j].k
        if j == len(self.frames) - 1:
            self.playing = False
        if j != i:
            self.revision += 1
        return j - i

    def shown_frame(self: Any) -> Any:
        with self.lock:
            return self.frames[self._shown_index()]

    # ------------------------------------------------------------------ what the views show
    def shown_snapshot(self: Any) -> Any:
        """The live snapshot, or (scrubbing or replaying) the recorded frame at the cursor."""
        with self.lock:
            if self.cursor is None and self.replaying is None:
                return self.snapshot()
            frames = list(self.frames)
            i = self._shown_index()
            f = frames[i]
            trails = _trails(frames[: i + 1], f.t, self.scenario.view.trail_seconds)
            return self._replay_snapshot(f, trails)

    def _replay_snapshot(self: Any, frame: Any, trails: np.ndarray) -> Any:
        """The kind's snapshot with the robots of ``frame``; live-only overlays blanked."""
        snap = self.snapshot()
        names = {f.name for f in dataclasses.fields(snap)}
        changes = dict(k=frame.k, t=frame.t, x=frame.x.copy(), heading=frame.heading.copy(), trails=trails,
                       revision=self.revision, live=False)
        changes.update(self._replay_blanks(frame))
        return dataclasses.replace(snap, **{k: v for k, v in changes.items() if k in names})

    def _replay_blanks(self: Any, frame: Any) -> dict[str, Any]:
        """Snapshot fields to replace for a recorded frame (a kind blanks its live overlays)."""
        return {}

    def twin_view(self: Any) -> tuple[np.ndarray, np.ndarray] | None:
        """Swarm B's robots and trails at the step shown (None without B, or if B has no such step)."""
        with self.lock:
            twin = self.twin
            if twin is None:
                return None
            with twin.lock:
                frames = list(twin.frames)
            k = self.frames[self._shown_index()].k
            ks = [f.k for f in frames]
            i = bisect.bisect_left(ks, k)
            if i == len(ks) or ks[i] != k:
                return None
            f = frames[i]
            return f.x.copy(), _trails(frames[: i + 1], f.t, twin.scenario.view.trail_seconds)

    def shown_metrics(self: Any, n: int) -> tuple[dict[str, np.ndarray], tuple[float, float]]:
        """The last ``n`` metric rows up to the time shown, and the time span of all ``n`` (the x range)."""
        m = self.metric_arrays()
        m = {k: v[-n:] for k, v in m.items()}
        t = m["t"]
        span = (float(t[0]), float(t[-1])) if len(t) else (0.0, 1.0)
        with self.lock:
            scrubbed = self.cursor is not None or self.replaying is not None
            t_shown = self.frames[self._shown_index()].t
        if scrubbed:
            keep = t <= t_shown + 1e-9
            m = {k: v[keep] for k, v in m.items()}
        return m, span

    # ------------------------------------------------------------------ replay files
    def recording(self: Any) -> Recording:
        """The recorded history (frames and metrics) with the preset and seed that made it."""
        with self.lock:
            frames = list(self.frames)
            metrics = np.array(self.metrics, dtype=float).reshape(-1, len(self.METRICS))
            if self.replaying is not None:
                version, edits = self.replaying.shoal, self.replaying.live_edits
            else:
                version, edits = shoal.__version__, self.live_edits + int(getattr(self, "edits", 0))
            meta = replay.make_meta(shoal=version, preset=self.scenario.model_dump(mode="json"),
                                    name=self.scenario.name, seed=int(self.scenario.sim.seed),
                                    kind=type(self).__name__, metrics=self.METRICS, live_edits=edits)
        return replay.from_frames(meta, [f.k for f in frames], [f.t for f in frames], [f.x for f in frames],
                                  [f.heading for f in frames], [f.status for f in frames], metrics)

    def export_replay(self: Any) -> bytes:
        return replay.to_bytes(self.recording())

    def check_replay(self: Any, rec: Recording) -> None:
        """Refuse a recording this kind of session cannot show (raises :class:`ReplayError`)."""
        d, expect = rec.x.shape[1], self.frames[-1].x.shape[-1]
        if d != expect:
            raise replay.ReplayError([f"x: positions have {d} columns but the preset's robots move in {expect}-D"])

    def enter_replay(self: Any, rec: Recording, check: tuple[bool | None, str]) -> None:
        """Show ``rec`` (already checked against this session's scenario) instead of the engine."""
        from .base_session import Frame

        self.check_replay(rec)
        with self.lock:
            self.playing = False
            self.twin = None
            frames: deque[Any] = deque()
            for i in range(rec.frames):
                x, heading, status = rec.robots(i)
                zeros = np.zeros_like(x)
                frames.append(Frame(k=int(rec.k[i]), t=float(rec.t[i]), x=x.copy(), u=zeros, a=zeros,
                                    heading=heading.copy(), status=status.copy()))
            self.frames = frames
            self._rows = int(len(rec.x))
            self.metrics = deque(maxlen=max(self.MAX_METRICS, len(rec.metrics)))
            if rec.metric_names == tuple(self.METRICS):
                self.metrics.extend(tuple(float(v) for v in row) for row in rec.metrics)
            self.cursor = frames[-1].k
            self.replaying = ReplayInfo(name=rec.name, seed=rec.seed, shoal=str(rec.meta["shoal"]),
                                        verified=check[0], check=check[1], live_edits=int(rec.meta["live_edits"]))
            self.revision += 1

    def leave_replay(self: Any) -> None:
        """Back to a live run of the scene's preset from step 0."""
        with self.lock:
            if self.replaying is not None:
                self._reset_locked(self.scenario.sim.seed)
                self.revision += 1


def _trails(frames: list[Any], t_now: float, horizon: float) -> np.ndarray:
    from .base_session import trail_array

    return trail_array(frames, t_now, horizon, *TRAIL_LIMITS)
