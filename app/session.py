"""One browser tab's simulation: the current scenario, the running swarm, playback and history.

No viser here: the GUI (``panels``) and the drawing (``scene``) call these methods, and so
can tests. Every public method takes ``lock``, because browser callbacks run on viser's
thread pool while the ticking thread advances the swarm.

Every change goes through the pydantic :class:`Scenario` first (``apply``): a value the model
refuses raises :class:`PresetError` and leaves both the scenario and the swarm untouched.
"""

from __future__ import annotations

import copy
import functools
import io as _io
import json
import math
import threading
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

import shoal
from shoal.engine.sim import Simulation
from shoal.presets import io as presets_io
from shoal.presets.build import build_simulation, law_for, objective_for, policy_for
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

TRAJECTORY_COLUMNS = ("run", "step", "t", "robot", "x", "y", "heading", "vx", "vy", "status")
_CSV_FORMAT = ["%d", "%d", "%.6f", "%d", "%.9g", "%.9g", "%.9g", "%.9g", "%.9g", "%d"]

MAX_UPLOAD_BYTES = 256 * 1024


def check_supported(scenario: Scenario) -> Scenario:
    """The browser app runs the Chapter 3 swarm; refuse scenes it cannot show (yet)."""
    problems = []
    if getattr(scenario, "world", None) is not None:
        problems.append("world: scenes with obstacles (Chapters 4-5) do not run in the browser app yet; "
                        "use `shoal run` for them")
    elif scenario.controller.mode not in ("raw", "physical"):
        problems.append(f"controller.mode: {scenario.controller.mode!r} needs a [world]; the browser app "
                        "offers 'raw' and 'physical'")
    if problems:
        raise PresetError(problems)
    return scenario


@functools.lru_cache(maxsize=1)
def app_presets() -> dict[str, str]:
    """Shipped presets the browser app can run, name → one-line description."""
    out = {}
    for name, description in presets_io.list_presets().items():
        try:
            check_supported(presets_io.load(name))
        except PresetError:
            continue
        out[name] = description
    return out


@dataclass(frozen=True)
class Frame:
    """The swarm (run 0) after step ``k``: what the trail, the phase plane and export need."""

    k: int
    t: float
    x: np.ndarray  # (N, d)
    u: np.ndarray  # (N, d)
    a: np.ndarray  # (N, d)
    heading: np.ndarray  # (N,)
    status: np.ndarray  # (N,)


@dataclass(frozen=True)
class Snapshot:
    """A consistent copy of what the arena draws, taken under the lock."""

    k: int
    t: float
    x: np.ndarray  # (N, d)
    heading: np.ndarray  # (N,)
    y: np.ndarray  # (N, d) personal bests
    yg: np.ndarray  # (d,) global best
    trails: np.ndarray  # (M, L, d) oldest first, M ≤ N
    revision: int


def _section_changed(old: Scenario, new: Scenario, name: str) -> bool:
    return getattr(old, name).model_dump() != getattr(new, name).model_dump()


class Session:
    """Simulation and playback state of one browser tab."""

    MAX_STEPS = 5000  # history ring buffer: at most this many steps ...
    MAX_ROWS = 400_000  # ... and at most this many (step, robot) rows
    MAX_METRICS = 5000

    def __init__(self, scenario: Scenario) -> None:
        check_supported(scenario)
        self.lock = threading.RLock()
        self.playing = False
        self.revision = 0  # bumps whenever the swarm changes (scene redraw)
        self.scene_revision = 0  # bumps when the arena or objective changes (static scene rebuild)
        self.selected_robot = 0
        self.selected_dim = 0
        self._load(scenario)

    # ------------------------------------------------------------------ loading
    def _load(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.sim: Simulation = build_simulation(scenario, runs=1)
        self._clear_history()
        self.scene_revision += 1

    def _clear_history(self) -> None:
        self._t0, self._k0 = 0.0, self.sim.state.k  # session clock origin (see ``clock``)
        self.frames: deque[Frame] = deque()
        self._rows = 0
        # per step: t, max |u|, max |u_j|, ω, ĉ
        self.metrics: deque[tuple[float, float, float, float, float]] = deque(maxlen=self.MAX_METRICS)
        self._record(None)

    def load_scenario(self, scenario: Scenario) -> None:
        """Replace the whole scene (preset switch, upload); refuses scenes the app cannot show."""
        check_supported(scenario)
        with self.lock:
            self._load(scenario)
            self.selected_robot = min(self.selected_robot, scenario.sim.robots - 1)
            self.selected_dim = min(self.selected_dim, scenario.sim.d - 1)
            self.revision += 1

    def load_preset(self, name: str) -> Scenario:
        scenario = presets_io.load(name)
        self.load_scenario(scenario)
        return scenario

    def load_upload(self, filename: str, content: bytes) -> Scenario:
        """Validate an uploaded TOML/JSON preset; replace the scene only if it is valid."""
        if len(content) > MAX_UPLOAD_BYTES:
            raise PresetError([f"{filename}: {len(content) / 1024:.0f} KiB is larger than the "
                               f"{MAX_UPLOAD_BYTES // 1024} KiB limit for a preset"])
        try:
            text = content.decode("utf-8")
        except UnicodeDecodeError:
            raise PresetError([f"{filename}: not UTF-8 text"]) from None
        lower = filename.lower()
        if lower.endswith(".json"):
            data = presets_io.parse_text(text, "json")
        elif lower.endswith(".toml"):
            data = presets_io.parse_text(text, "toml")
        else:  # no telling extension: JSON starts with '{'
            data = presets_io.parse_text(text, "json" if text.lstrip().startswith("{") else "toml")
        scenario = presets_io.validate(data)
        self.load_scenario(scenario)
        return scenario

    # ------------------------------------------------------------------ changes
    def propose(self, changes: dict[str, Any]) -> Scenario:
        """The scenario with ``changes`` (dotted path → value) applied, validated; nothing is changed."""
        with self.lock:
            data = copy.deepcopy(self.scenario.model_dump(mode="json"))
        for key, value in changes.items():
            presets_io.set_dotted(data, key, value)
        return presets_io.validate(data)

    def apply(self, changes: dict[str, Any]) -> Scenario:
        """Validate ``changes`` and apply them to the running swarm at once, without restarting.

        Raises :class:`PresetError` (nothing changed) when the model refuses the result.
        """
        with self.lock:
            new = self.propose(changes)
            self._adopt(new)
            return new

    def _adopt(self, new: Scenario) -> None:
        old, sim = self.scenario, self.sim
        if (new.sim.d != old.sim.d or _section_changed(old, new, "init")):
            self._load(new)
            self.revision += 1
            return
        self.scenario = new
        if _section_changed(old, new, "controller"):
            self._t0, self._k0 = self.clock(), sim.state.k  # keep the time axis continuous
            sim.policy = policy_for(new.controller)
            sim.law = law_for(new.controller)
            sim.dt = float(new.controller.dt)
        if new.sim.robots != old.sim.robots:
            sim.set_robots(new.sim.robots)
            self.selected_robot = min(self.selected_robot, new.sim.robots - 1)
        if _section_changed(old, new, "bests"):
            sim.attractors = new.bests.attractors
            sim.pbest_order = new.bests.pbest_order
        if _section_changed(old, new, "objective"):
            sim.set_objective(objective_for(new.objective))
            self.scene_revision += 1
        if _section_changed(old, new, "arena"):
            self.scene_revision += 1
        if new.sim.seed != old.sim.seed:
            self._reset_locked(new.sim.seed)
        self.revision += 1

    # ------------------------------------------------------------------ playback
    def play(self) -> None:
        with self.lock:
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

    def step(self, n: int = 1) -> int:
        """Advance ``n`` ticks. Pauses when the preset's ``sim.steps`` is reached; returns the steps done."""
        done = 0
        with self.lock:
            for _ in range(n):
                info = self.sim.step()
                self._record(info)
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
        s = self.sim.state
        frame = Frame(k=s.k, t=self.clock(), x=s.x[0].copy(), u=s.u[0].copy(), a=s.a[0].copy(),
                      heading=s.heading[0].copy(), status=s.status[0].copy())
        self.frames.append(frame)
        self._rows += frame.x.shape[0]
        while len(self.frames) > 1 and (len(self.frames) > self.MAX_STEPS or self._rows > self.MAX_ROWS):
            self._rows -= self.frames.popleft().x.shape[0]
        omega, c_hat = self.coefficients()
        speed = np.linalg.norm(s.u[0], axis=-1)
        self.metrics.append((self.clock(), float(speed.max()), float(np.abs(s.u[0]).max()), omega, c_hat))

    def coefficients(self) -> tuple[float, float]:
        """The (ω, ĉ) the controller uses at the current time (means over robots for per-robot policies)."""
        with self.lock:
            omega, c = self.sim.policy.coefficients(self.sim.t, self.sim.dt, self.sim.d)
            c = np.asarray(c, dtype=float)
            c_hat = float(np.sum(c.reshape(c.shape[0], -1).mean(axis=1))) if c.ndim else float(c)
            return float(np.mean(omega)), c_hat

    def readout(self) -> dict[str, float]:
        """Derived quantities for the panel: ω, ĉ, β, U, U_j, A+, A− (NaN where undefined)."""
        with self.lock:
            omega, c_hat = self.coefficients()
            d, dt = self.sim.d, self.sim.dt
            adapted = self.sim.law.adapted
            bounded = adapted and 0.0 <= omega < 1.0
            U_j = c_hat / (1.0 - omega) if bounded else math.nan
            A_plus = c_hat * math.sqrt(d) / dt if adapted else math.nan
            return {
                "omega": omega, "c_hat": c_hat, "beta": (1.0 - omega) if bounded else math.nan,
                "U": U_j * math.sqrt(d), "U_j": U_j, "A_plus": A_plus, "A_minus": 2 * A_plus,
                "t": self.clock(), "k": float(self.sim.state.k), "best": float(self.sim.state.f_yg[0]),
                "outside": float(self.outside_arena()),
            }

    def outside_arena(self) -> int:
        """How many robots are outside the arena square (a diverging swarm leaves the picture)."""
        with self.lock:
            x = self.sim.state.x[0, :, :2]
            return int(np.sum(np.any(np.abs(x) > self.scenario.arena.half_size, axis=-1)))

    def snapshot(self, max_trails: int = 80, max_trail_points: int = 40) -> Snapshot:
        """What the arena draws now: positions, bests and trails of the last ``view.trail_seconds``."""
        with self.lock:
            s = self.sim.state
            t_now = self.clock()
            horizon = self.scenario.view.trail_seconds
            recent = [f for f in self.frames if f.t >= t_now - horizon - 1e-9]
            if len(recent) > max_trail_points:
                # keep every stride-th step by step number (not by position in the window), so
                # the kept points stay put from frame to frame instead of shimmering
                stride = -(-len(recent) // (max_trail_points - 1))
                recent = [f for f in recent[:-1] if f.k % stride == 0] + recent[-1:]
            if len(recent) >= 2:
                m = min(min(f.x.shape[0] for f in recent), max_trails)
                trails = np.stack([f.x[:m] for f in recent], axis=1)
            else:
                trails = np.zeros((0, 0, self.sim.d))
            return Snapshot(k=s.k, t=t_now, x=s.x[0].copy(), heading=s.heading[0].copy(), y=s.y[0].copy(),
                            yg=s.yg[0].copy(), trails=trails, revision=self.revision)

    def particle_history(self, robot: int, dim: int, n: int = 120) -> tuple[np.ndarray, np.ndarray]:
        """The last ``n`` (u_j, a_j) of one particle and dimension, oldest first."""
        with self.lock:
            frames = list(self.frames)[-n:]
            pts = [(f.u[robot, dim], f.a[robot, dim]) for f in frames
                   if robot < f.u.shape[0] and dim < f.u.shape[1]]
            arr = np.array(pts, dtype=float).reshape(-1, 2)
            return arr[:, 0], arr[:, 1]

    def metric_arrays(self) -> dict[str, np.ndarray]:
        with self.lock:
            m = np.array(self.metrics, dtype=float).reshape(-1, 5)
        return {"t": m[:, 0], "max_speed": m[:, 1], "max_component": m[:, 2], "omega": m[:, 3], "c_hat": m[:, 4]}

    # ------------------------------------------------------------------ export
    def trajectory_rows(self) -> np.ndarray:
        """Rows ``run,step,t,robot,x,y,heading,vx,vy,status`` of the buffered history (run 0)."""
        with self.lock:
            frames = list(self.frames)
        blocks = []
        for f in frames:
            n, d = f.x.shape
            comp = lambda a, j: a[:, j] if d > j else np.zeros(n)  # noqa: E731
            blocks.append(np.column_stack([
                np.zeros(n), np.full(n, f.k), np.full(n, f.t), np.arange(n),
                comp(f.x, 0), comp(f.x, 1), f.heading, comp(f.u, 0), comp(f.u, 1), f.status,
            ]))
        return np.vstack(blocks) if blocks else np.zeros((0, len(TRAJECTORY_COLUMNS)))

    def export_csv(self) -> bytes:
        buf = _io.StringIO()
        buf.write(",".join(TRAJECTORY_COLUMNS) + "\n")
        np.savetxt(buf, self.trajectory_rows(), fmt=_CSV_FORMAT, delimiter=",")
        return buf.getvalue().encode()

    def export_json(self) -> bytes:
        with self.lock:
            preset = self.scenario.model_dump(mode="json")
            seed = self.sim.seed
        rows = self.trajectory_rows()
        ints = {"run", "step", "robot", "status"}
        trajectories = [
            {c: (int(v) if c in ints else float(v)) for c, v in zip(TRAJECTORY_COLUMNS, row)} for row in rows
        ]
        doc = {"preset": preset, "seed": seed, "version": shoal.__version__, "trajectories": trajectories}
        return json.dumps(doc, separators=(",", ":")).encode()

    def preset_toml(self) -> bytes:
        with self.lock:
            return presets_io.to_toml(self.scenario).encode()
