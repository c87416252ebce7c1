"""What every tab's simulation shares, whatever it runs: scenario changes through the model,
playback, the history ring buffer, trails and export.

Two kinds of session build on it: :class:`shoal.app.session.Session` (the Chapter 3 swarm in
free space) and :class:`shoal.app.fleet_session.FleetSession` (Chapter 4–5 robots with bodies
in an obstacle world). A subclass says how to build its engine from a scenario (``_build``),
how to take a validated change without restarting (``_adopt``) and what to record per step
(``_metric_row``, ``METRICS``).

No viser here. Every public method takes ``lock``: browser callbacks run on viser's thread
pool while the ticking thread advances the engine.
"""

from __future__ import annotations

import copy
import io as _io
import json
import threading
from collections import deque
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

import shoal
from shoal.engine.core.recorder import TRAJECTORY_COLUMNS, trajectory_header, write_trajectory
from shoal.presets import io as presets_io
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from .compare import CompareMixin
from .limits import check_app_limits
from .timeline import TimelineMixin

MAX_UPLOAD_BYTES = 256 * 1024


def parse_upload(filename: str, content: bytes) -> Scenario:
    """A validated scenario from an uploaded TOML/JSON preset, or :class:`PresetError`."""
    if len(content) > MAX_UPLOAD_BYTES:
        raise PresetError([f"{filename}: {len(content) / 1024:.0f} KiB is larger than the "
                           f"{MAX_UPLOAD_BYTES // 1024} KiB limit for a preset"])
    try:
        text = content.decode("utf-8")
    except UnicodeDecodeError:
        raise PresetError([f"{filename}: not UTF-8 text"]) from None
    lower = filename.lower()
    if lower.endswith(".json"):
        kind = "json"
    elif lower.endswith(".toml"):
        kind = "toml"
    else:  # no telling extension: JSON starts with '{'
        kind = "json" if text.lstrip().startswith("{") else "toml"
    return presets_io.validate(presets_io.parse_text(text, kind))


@dataclass(frozen=True)
class Frame:
    """The robots (run 0) after step ``k``: what trails and export need (``a`` only for Ch. 3)."""

    k: int
    t: float
    x: np.ndarray  # (N, d)
    u: np.ndarray  # (N, d)
    heading: np.ndarray  # (N,)
    status: np.ndarray  # (N,)
    a: np.ndarray | None = None  # (N, d)


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


class BaseSession(CompareMixin, TimelineMixin):
    """Scenario, engine (``sim``), playback and history of one browser tab; optionally a
    swarm B in lock-step (``twin``, see :mod:`.compare`) and a timeline cursor or a loaded
    replay (``cursor``, ``replaying``, see :mod:`.timeline`)."""

    MAX_STEPS = 5000  # history ring buffer: at most this many steps ...
    MAX_ROWS = 400_000  # ... and at most this many (step, robot) rows
    MAX_METRICS = 5000
    METRICS: ClassVar[tuple[str, ...]] = ("t",)  # names of the per-step metric columns
    NOTES: ClassVar[str] = "ch3"  # teaching notes shown for this kind of scene

    def __init__(self, scenario: Scenario) -> None:
        self.check(scenario)
        self.lock = threading.RLock()
        self.playing = False
        self.revision = 0  # bumps whenever the robots change (scene redraw)
        self.scene_revision = 0  # bumps when the static scene changes (rebuild)
        self.selected_robot = 0
        self.twin: BaseSession | None = None  # swarm B (compare), stepped with this one
        self.overrides: dict[str, Any] = {}  # B = this scenario with these fields changed
        self._load(scenario)

    # ------------------------------------------------------------------ subclass hooks
    @classmethod
    def accepts(cls, scenario: Scenario) -> bool:
        """Can this kind of session run ``scenario``?"""
        raise NotImplementedError

    @classmethod
    def check(cls, scenario: Scenario) -> Scenario:
        if not cls.accepts(scenario):
            raise PresetError([f"{scenario.name}: this scene needs another kind of session"])
        return scenario

    def _build(self, scenario: Scenario) -> Any:
        """The engine object for ``scenario`` (raise :class:`PresetError` if it cannot be built)."""
        raise NotImplementedError

    def _adopt(self, new: Scenario) -> None:
        """Take the validated ``new`` scenario, at once where the engine allows."""
        raise NotImplementedError

    def _frame(self) -> Frame:
        """The first run's robots now, for the history ring buffer."""
        s = self.sim.state
        return Frame(k=s.k, t=self.clock(), x=s.x[0].copy(), u=s.u[0].copy(), heading=s.heading[0].copy(),
                     status=s.status[0].copy())

    def select(self, robot: int) -> None:
        """Make ``robot`` the one whose details the panels and the scene show."""
        with self.lock:
            self.selected_robot = int(min(max(robot, 0), self.sim.robots - 1))
            self.revision += 1

    def _metric_row(self, info: Any) -> tuple[float, ...]:
        """One row of ``METRICS`` for the current state (``info`` is None at step 0)."""
        raise NotImplementedError

    # ------------------------------------------------------------------ loading
    def _load(self, scenario: Scenario) -> None:
        check_app_limits(scenario)  # a shared server: no scene far beyond the sliders' reach
        sim = self._build(scenario)  # may refuse: then nothing has changed
        self.scenario = scenario
        self.sim = sim
        self._clear_history()
        self.scene_revision += 1

    def _clear_history(self) -> None:
        self._t0, self._k0 = 0.0, self.sim.state.k  # session clock origin (see ``clock``)
        self.frames: deque[Frame] = deque()
        self._rows = 0
        self.metrics: deque[tuple[float, ...]] = deque(maxlen=self.MAX_METRICS)
        self.cursor: int | None = None  # the recorded step shown (None: live)
        self.replaying = None  # a loaded replay shown instead of the engine (timeline.ReplayInfo)
        self.live_edits = 0  # changes made while the run went on (a replay of it cannot be re-simulated)
        self._record(None)

    def load_scenario(self, scenario: Scenario) -> None:
        """Replace the whole scene (preset switch, upload); refuses scenes of another kind."""
        self.check(scenario)
        with self.lock:
            self._load(scenario)
            self.twin = None  # a new scene: no swarm B until asked again
            self.selected_robot = min(self.selected_robot, scenario.sim.robots - 1)
            self.revision += 1

    def load_preset(self, name: str) -> Scenario:
        """Load the shipped preset ``name`` (never a file)."""
        scenario = presets_io.load_shipped(name)
        self.load_scenario(scenario)
        return scenario

    def load_upload(self, filename: str, content: bytes) -> Scenario:
        """Validate an uploaded TOML/JSON preset; replace the scene only if it is valid."""
        scenario = parse_upload(filename, content)
        self.load_scenario(scenario)
        return scenario

    # ------------------------------------------------------------------ changes
    def propose(self, changes: dict[str, Any]) -> Scenario:
        """The scenario with ``changes`` (dotted path → value) applied, validated; nothing is changed."""
        with self.lock:
            data = copy.deepcopy(self.scenario.model_dump(mode="json"))
        for key, value in changes.items():
            presets_io.set_dotted(data, key, value)
        return check_app_limits(presets_io.validate(data))

    def apply(self, changes: dict[str, Any]) -> Scenario:
        """Validate ``changes`` and apply them, without restarting where the engine allows.

        Raises :class:`PresetError` (nothing changed) when the model refuses the result. Swarm B
        takes the same change (keeping its overrides); a change B cannot take is refused too.
        A change beyond the view ends a replay (a live run of the preset starts).
        """
        with self.lock:
            new = self.propose(changes)
            self.check(new)
            new_b = self._twin_propose(new)
            view_only = all(k.startswith("view.") for k in changes)
            if self.replaying is not None and not view_only:
                self.leave_replay()
            elif not view_only:
                self.cursor = None  # a change applies to the live run: show it
            old_b = self._twin_adopt(new_b)
            before = self.frames
            try:
                self._adopt(new)
            except PresetError:
                self._twin_adopt(old_b)
                raise
            if self.frames is before and not view_only:
                self.live_edits += 1
            return new

    def _keep_clock(self) -> None:
        """Call before Δt changes mid-run: the time axis continues from where it was."""
        self._t0, self._k0 = self.clock(), self.sim.state.k

    # ------------------------------------------------------------------ playback
    def play(self) -> None:
        """Run on from the live end (a replay: on through the recording, from its start if at the end)."""
        with self.lock:
            if self.replaying is None:
                self.cursor = None
            elif self.frames and self.cursor == self.frames[-1].k:
                self.cursor = self.frames[0].k
                self.revision += 1
            self.playing = True

    def pause(self) -> None:
        with self.lock:
            self.playing = False

    def reset(self, seed: int | None = None) -> None:
        """Back to step 0; with ``seed`` also change the scenario's seed (validated)."""
        with self.lock:
            if seed is not None and seed != self.scenario.sim.seed:
                self.apply({"sim.seed": int(seed)})  # resets as part of the change
                return
            self._reset_locked(self.scenario.sim.seed)
            self.revision += 1

    def _reset_locked(self, seed: int) -> None:
        self.sim.reset(seed)
        self._clear_history()
        if self.twin is not None:
            with self.twin.lock:
                self.twin._reset_locked(self.twin.scenario.sim.seed)

    def step(self, n: int = 1) -> int:
        """Advance ``n`` ticks (swarm B too). Pauses when the preset's ``sim.steps`` is reached;
        returns the steps done. A replay moves ``n`` recorded frames on instead."""
        done = 0
        with self.lock:
            if self.replaying is not None:
                return self._advance_cursor(n)
            if self.cursor is not None:
                self.cursor = None
                self.revision += 1
            for _ in range(n):
                info = self.sim.step()
                self._record(info)
                if self.twin is not None:
                    self.twin.step(1)
                done += 1
                if self.sim.state.k == self.scenario.sim.steps:
                    self.playing = False
                    break
            if done:
                self.revision += 1
        return done

    @property
    def finished(self) -> bool:
        with self.lock:
            return self.sim.state.k >= self.scenario.sim.steps

    # ------------------------------------------------------------------ history
    def clock(self) -> float:
        """Seconds since reset. Equals the engine's ``k·Δt`` until Δt is changed mid-run; after that
        it keeps counting from where it was, so trails and plots never jump back in time."""
        return self._t0 + (self.sim.state.k - self._k0) * self.sim.dt

    def _record(self, info: Any) -> None:
        frame = self._frame()
        self.frames.append(frame)
        self._rows += frame.x.shape[0]
        while len(self.frames) > 1 and (len(self.frames) > self.MAX_STEPS or self._rows > self.MAX_ROWS):
            self._rows -= self.frames.popleft().x.shape[0]
        self.metrics.append(self._metric_row(info))

    def metric_arrays(self) -> dict[str, np.ndarray]:
        """The recorded metrics as columns named by ``METRICS``."""
        with self.lock:
            m = np.array(self.metrics, dtype=float).reshape(-1, len(self.METRICS))
        return {name: m[:, j] for j, name in enumerate(self.METRICS)}

    def trails(self, max_trails: int = 80, max_trail_points: int = 40) -> np.ndarray:
        """(M, L, d) trails of the last ``view.trail_seconds``, ending at the robots."""
        with self.lock:
            return trail_array(list(self.frames), self.clock(), self.scenario.view.trail_seconds,
                               max_trails, max_trail_points)

    # ------------------------------------------------------------------ export
    def trajectory_rows(self) -> np.ndarray:
        """Rows ``run,step,t,robot,x,y,heading,vx,vy,status`` of the buffered history (run 0)."""
        with self.lock:
            frames = list(self.frames)
        return frame_rows(frames)

    def export_csv(self) -> bytes:
        buf = _io.StringIO()
        buf.write(trajectory_header(2) + "\n")
        write_trajectory(buf, self.trajectory_rows())
        return buf.getvalue().encode()

    def export_extra(self) -> dict[str, Any]:
        """More top-level entries for the JSON export (a subclass adds its own)."""
        return {}

    def export_json(self) -> bytes:
        with self.lock:
            preset = self.scenario.model_dump(mode="json")
            seed = self.sim.seed
            extra = self.export_extra()
        rows = self.trajectory_rows()
        ints = {"run", "step", "robot", "status"}
        trajectories = [
            {c: (int(v) if c in ints else float(v)) for c, v in zip(TRAJECTORY_COLUMNS, row)} for row in rows
        ]
        doc = {"preset": preset, "seed": seed, "version": shoal.__version__, **extra,
               "trajectories": trajectories}
        return json.dumps(doc, separators=(",", ":")).encode()

    def preset_toml(self) -> bytes:
        with self.lock:
            return presets_io.to_toml(self.scenario).encode()
