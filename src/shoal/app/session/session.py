"""One browser tab's simulation: scenario, engine, playback, history, timeline and swarm B.

A :class:`Session` is the same for every scene kind; what differs (how to build the engine,
which changes need a new one, what to record and draw) is its kind's :class:`~.driver.Driver`.
It is composed of small parts: a :class:`~.history.History` (frames and metric rows), a
:class:`~.timeline.Timeline` over it (scrubbing, replays) and, when comparing, a
:class:`~.twin.Twin` (swarm B, itself a session of the same kind).

Every change goes through the pydantic :class:`Scenario` first (``apply``): a value the model
refuses raises :class:`PresetError` and leaves both the scenario and the engine untouched.

No viser here. Every public method takes ``lock``: browser callbacks run on viser's thread
pool while the ticking thread advances the engine.
"""

from __future__ import annotations

import copy
import dataclasses
import io as _io
import json
import threading
from typing import Any, Protocol

import numpy as np

import shoal
from shoal.engine.core.recorder import TRAJECTORY_COLUMNS, metric_table, trajectory_header, write_trajectory
from shoal.presets import io as presets_io
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from .. import replay
from ..limits import check_app_limits, check_recording
from ..replay import Recording
from ..warmup import WARMUP
from .driver import Driver
from .history import HISTORY_BUDGET, TRAIL_LIMITS, Frame, History, Trails
from .lifecycle import Lifecycle
from .snapshot import Snapshot
from .timeline import ReplayInfo, Timeline
from .twin import Twin, twin_scenario
from .upload import parse_upload


class SessionKind(Protocol):
    """A scene kind as a session sees it (the whole plug-in is :class:`shoal.app.kinds.base.AppKind`)."""

    @property
    def name(self) -> str: ...

    def check(self, scenario: Scenario) -> Scenario:
        """``scenario`` if this kind shows it, else :class:`PresetError` saying why not."""
        ...

    def driver(self, session: Session) -> Driver: ...


class Session:
    """Scenario, engine (``sim``), playback and history of one browser tab."""

    def __init__(self, scenario: Scenario, kind: SessionKind) -> None:
        self.kind = kind
        self.check(scenario)
        self.lock = threading.RLock()
        self.lifecycle = Lifecycle()  # playing or not, and what happens at the last step
        self.revision = 0  # bumps whenever the robots change (scene redraw)
        self.scene_revision = 0  # bumps when the static scene changes (rebuild)
        self.selected_robot = 0  # the robot the panels and the view single out
        self.selected_neighbour: int | None = None  # a second robot (a pair to inspect; None: the kind picks)
        self.selected_dim = 0  # the coordinate a per-dimension plot shows
        self.compare: Twin[Session] | None = None  # swarm B, stepped with this one
        self.live_edits = 0  # changes made while the run went on (a replay of it cannot be re-simulated)
        self.driver = kind.driver(self)
        self.history = History(("t",))
        self.timeline = Timeline(self.history)
        self.history_budget = HISTORY_BUDGET  # numbers this tab's histories hold (A's and B's together)
        self._load(scenario)

    def check(self, scenario: Scenario) -> Scenario:
        return self.kind.check(scenario)

    # ------------------------------------------------------------------ what the parts share
    @property
    def playing(self) -> bool:
        return self.lifecycle.playing

    @playing.setter
    def playing(self, value: bool) -> None:
        self.lifecycle.playing = bool(value)

    @property
    def k(self) -> int:
        """The engine's step."""
        return int(self.sim.state.k)

    @property
    def robots(self) -> int:
        return int(self.sim.state.x.shape[1])

    @property
    def engine_name(self) -> str:
        return type(self.sim).__name__

    @property
    def frames(self) -> Any:
        """The recorded frames, oldest first (see :class:`History`)."""
        return self.history.frames

    @property
    def cursor(self) -> int | None:
        return self.timeline.cursor

    @property
    def replaying(self) -> ReplayInfo | None:
        return self.timeline.replaying

    @property
    def twin(self) -> Session | None:
        """Swarm B's session (None without B)."""
        return self.compare.b if self.compare is not None else None

    @property
    def overrides(self) -> dict[str, Any]:
        """How B differs from A ({} without B)."""
        return self.compare.overrides if self.compare is not None else {}

    def select(self, robot: int) -> None:
        """Single out ``robot`` for the panels and the view."""
        with self.lock:
            self.selected_robot = int(min(max(robot, 0), self.robots - 1))
            self.revision += 1

    def select_neighbour(self, neighbour: int | None) -> None:
        """The second robot singled out (None: the kind picks one)."""
        with self.lock:
            self.selected_neighbour = None if neighbour is None else int(min(max(neighbour, 0), self.robots - 1))
            self.revision += 1

    def robot_near(self, x: float, y: float, tol: float, body: float = 0.0) -> int | None:
        """The robot within ``tol`` of (x, y) (of its body of radius ``body``), nearest first."""
        with self.lock:
            d = np.hypot(*(self.sim.state.x[0, :, :2] - (x, y)).T) - body
            return int(np.argmin(d)) if d.size and d.min() <= tol else None

    # ------------------------------------------------------------------ loading
    def _load(self, scenario: Scenario) -> None:
        check_app_limits(scenario)  # a shared server: no scene far beyond the sliders' reach
        WARMUP.prefer(scenario)  # a scene whose kernels run as Python meanwhile has them compiled next
        sim = self.driver.build(scenario)  # may refuse: then nothing has changed
        WARMUP.use(sim, scenario)  # its numpy tick while its kernels compile (the same numbers)
        self.scenario = scenario
        self.sim = sim
        self.driver.loaded()
        self._clear_history()
        self.scene_revision += 1

    def _clear_history(self, t0: float = 0.0) -> None:
        self._t0, self._k0 = float(t0), self.k  # session clock origin (see ``clock``)
        self.history.clear()
        self.history.names = tuple(self._metrics(self.sim.info()))
        self.timeline.clear()
        self.live_edits = 0
        self.driver.cleared()
        self._record(None)

    def _clamp_selection(self) -> None:
        self.selected_robot = min(self.selected_robot, self.robots - 1)
        self.selected_dim = min(self.selected_dim, self.scenario.sim.d - 1)

    def load_scenario(self, scenario: Scenario, *, play: bool = True) -> None:
        """Replace the whole scene (preset switch, upload) and play it (``play=False``: paused at
        step 0, as a lesson's *Set up* wants it); refuses scenes of another kind."""
        self.check(scenario)
        with self.lock:
            self._load(scenario)
            self.compare = None  # a new scene: no swarm B until asked again
            self._share_budget(None)
            self._clamp_selection()
            self.playing = play  # every scene opens playing
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
        if data.get("world") and any(k.startswith("world.") and k != "world.obstacles" for k in changes):
            data["world"].pop("obstacles", None)  # a new generator setting lays its world out afresh
        for key, value in changes.items():
            presets_io.set_dotted(data, key, value)
        return check_app_limits(presets_io.validate(data))

    def apply(self, changes: dict[str, Any]) -> Scenario:
        """Validate ``changes`` and apply them, without restarting where the engine allows.

        Raises :class:`PresetError` (nothing changed) when the model refuses the result. Swarm B
        takes the same change (keeping its overrides); a change B cannot take is refused too.
        A change beyond the view ends a replay (a live run of the preset starts), and starts a
        finished run again from step 0 with the new values.
        """
        with self.lock:
            new = self.propose(changes)
            self.check(new)
            new_b = self.compare.propose(new) if self.compare is not None else None
            view_only = all(k.startswith("view.") for k in changes)
            was_finished = self.finished and self.replaying is None
            if self.replaying is not None and not view_only:
                self.leave_replay()
            elif not view_only:
                self.timeline.cursor = None  # a change applies to the live run: show it
            old_b = self.compare.adopt(new_b) if self.compare is not None and new_b is not None else None
            before = self.history.epoch
            try:
                self.adopt(new)
            except PresetError:
                if self.compare is not None and old_b is not None:
                    self.compare.adopt(old_b)
                raise
            if was_finished and not view_only:
                if self.history.epoch == before:  # taken by the running engine: start it again
                    self.restart(self.scenario.sim.seed)
                self.playing = True
            if self.history.epoch == before and not view_only:
                self.live_edits += 1
            return new

    def adopt(self, new: Scenario) -> None:
        """Take the validated ``new`` scenario: into the running engine, or a new one where the kind
        needs it (the lock held)."""
        old = self.scenario
        if self.driver.rebuilds(old, new):
            self._load(new)  # builds first: a refused scene leaves everything as it was
        else:
            t, k, dt = self.clock(), self.k, self.driver.dt()
            try:
                self.sim.retune(**self.driver.live(old, new))  # from the next step; refused: nothing changed
            except ValueError as err:
                raise PresetError([str(err)]) from None
            self.scenario = new
            if self.driver.dt() != dt:  # the time axis continues from where it was
                self._t0, self._k0 = t, k
            if any(getattr(old, s) != getattr(new, s) for s in self.driver.scene_sections):
                self.scene_revision += 1
            if new.sim.seed != old.sim.seed:
                self.restart(new.sim.seed)
        self._clamp_selection()
        self.revision += 1

    # ------------------------------------------------------------------ playback
    @property
    def at_end(self) -> str:
        """What the run does at its last step: ``stop``, ``loop`` or ``run on`` (see :mod:`.lifecycle`)."""
        return self.lifecycle.at_end

    def choose_at_end(self, choice: str) -> None:
        """Set the end rule (ValueError for anything else); a run already past its last step
        that is now to stop there is finished."""
        with self.lock:
            self.lifecycle.choose(choice)
            if self.finished:
                self.playing = False

    @property
    def finished(self) -> bool:
        """Has the run stopped at its last step (the end rule is ``stop``)?"""
        with self.lock:
            return self.lifecycle.finished(self.k, self.scenario.sim.steps)

    def shown_step(self) -> tuple[int, float, int] | None:
        """(step, time, last recorded step) of the frame the arena shows while scrubbing or
        replaying; None at the live end."""
        with self.lock:
            if self.timeline.live:
                return None
            i = self.timeline.shown_index()
            return int(self.history.ks[i]), float(self.history.ts[i]), int(self.history.ks[-1])

    def progress(self, unit: str = "step") -> str:
        """The status line's ``step k/N`` (never beyond N over N)."""
        with self.lock:
            return self.lifecycle.progress(self.k, self.scenario.sim.steps, unit)

    def play(self) -> None:
        """Run on from the live end (a replay: on through the recording, from its start if at the
        end). A finished run starts again from step 0 with the current values."""
        with self.lock:
            if self.replaying is None:
                self.timeline.cursor = None
                if self.finished:
                    self.restart(self.scenario.sim.seed)
                    self.revision += 1
            elif self.timeline.rewind_if_at_end():
                self.revision += 1
            self.playing = True

    def pause(self) -> None:
        """Stop playing. It takes no lock: a Pause never waits for the step the ticker has in hand,
        and the steps left in the ticker's batch see it (:meth:`play_step`)."""
        self.playing = False

    def reset(self, seed: int | None = None) -> None:
        """Back to step 0 with the current values; with ``seed`` also change the scenario's seed
        (validated). A playing run plays on, and so does one that had finished. A replay goes
        back to its first step (a new seed leaves it for a live run with that seed)."""
        with self.lock:
            if self.replaying is not None and (seed is None or seed == self.scenario.sim.seed):
                self.timeline.rewind()
                self.revision += 1
                return
            play = self.playing or self.finished
            if seed is not None and seed != self.scenario.sim.seed:
                self.apply({"sim.seed": int(seed)})  # resets as part of the change
            else:
                self.restart(self.scenario.sim.seed)
                self.revision += 1
            self.playing = play

    def resume(self, engine: dict[str, Any], t: float) -> None:
        """Go on from an engine state taken elsewhere (``sim.snapshot()`` of an engine built from this
        scenario: a take-over), at session time ``t``: the engine restored, the history starting
        at its step. Raises ``SnapshotError`` (nothing recorded) when the state does not fit."""
        with self.lock:
            self.sim.restore(engine)
            self._clear_history(t)
            self.revision += 1

    def restart(self, seed: int) -> None:
        """The engine back to step 0 with ``seed``, the history cleared, swarm B too (the lock held)."""
        self.sim.reset(seed)
        self._clear_history()
        if self.compare is not None:
            self.compare.restart()

    def step(self, n: int = 1) -> int:
        """Advance up to ``n`` ticks (swarm B too) by the end rule: at the preset's ``sim.steps``
        the run stops (pauses, finished), loops to step 0 or runs on. A call on a finished run
        starts it again from step 0. Returns the steps done. A replay moves ``n`` recorded frames
        on instead."""
        done = 0
        with self.lock:
            if self.replaying is not None:
                moved, at_end = self.timeline.advance(n)
                if at_end:
                    self.playing = False
                if moved:
                    self.revision += 1
                return moved
            if self.timeline.cursor is not None:
                self.timeline.cursor = None
                self.revision += 1
            if self.finished:
                self.restart(self.scenario.sim.seed)
            steps = self.scenario.sim.steps
            for _ in range(n):
                rule = self.lifecycle.at_last(self.k, steps)
                if rule == "restart":
                    self.restart(self.scenario.sim.seed)
                self._advance()
                done += 1
                if self.lifecycle.finished(self.k, steps):
                    self.playing = False
                    break
            if done:
                self.revision += 1
        return done

    def play_step(self) -> int:
        """One step if the run is playing (the ticker's call): a Pause that arrives between the
        steps of a tick stops the rest of them."""
        with self.lock:
            return self.step(1) if self.playing else 0

    def advance(self, n: int = 1) -> int:
        """``n`` engine steps regardless of the end rule (swarm B follows A this way)."""
        n = max(int(n), 0)
        with self.lock:
            for _ in range(n):
                self._advance()
            if n:
                self.revision += 1
        return n

    def _advance(self) -> None:
        """One engine step, recorded, and swarm B's (the lock held)."""
        self.driver.before_step()
        WARMUP.use(self.sim, self.scenario)  # onto the compiled tick once its kernels are ready
        info = self.sim.step()
        self._record(info)
        if self.compare is not None:
            self.compare.step()

    # ------------------------------------------------------------------ swarm B
    def enable_compare(self, overrides: dict[str, Any]) -> None:
        """Build B from A's scenario with ``overrides`` and restart A and B from step 0 together.
        Raises :class:`PresetError` (nothing changed) when B's scenario is refused."""
        with self.lock:
            if self.replaying is not None:
                raise PresetError(["compare: a replay is shown; press Reset for a live run first"])
            twin = Twin.of(self.scenario, overrides, lambda sc: Session(sc, self.kind))
            self.compare = None  # A restarts alone, then B joins it at step 0: a reader that does not
            self._share_budget(twin.b)
            self.restart(self.scenario.sim.seed)  # take the lock never sees B beside an old A
            twin.restart()
            self.compare = twin
            self.revision += 1

    def disable_compare(self) -> None:
        with self.lock:
            self.compare = None
            self._share_budget(None)
            self.revision += 1

    def _share_budget(self, b: Session | None, replay_twin: bool = False) -> None:
        """A's history takes the tab's whole budget, or half of it with swarm B (live ``b``, or a
        replay's B frames), B's the other half (the lock held)."""
        two = b is not None or replay_twin
        share = self.history_budget // (2 if two else 1)
        self.history.budget = share
        self.timeline.twin.budget = share
        if b is not None:
            b.history.budget = share

    def twin_metric(self, name: str, t: np.ndarray) -> np.ndarray | None:
        """B's metric ``name`` at A's times ``t`` (None without B)."""
        compare = self.compare
        return compare.metric(name, t) if compare is not None else None

    def twin_view(self) -> tuple[np.ndarray, Trails] | None:
        """Swarm B's robots and trails at the step shown (None without B, or if B has no such step);
        in a replay, B as it was recorded."""
        with self.lock:
            k = int(self.history.ks[self.timeline.shown_index()])
            if self.replaying is not None:
                twin = self.timeline.twin
                return twin.robots_at(k, self.scenario.view.trail_seconds) if len(twin.frames) else None
            if self.compare is None:
                return None
            return self.compare.at(k)

    def _twin_record(self) -> tuple[list[Frame], dict[str, Any] | None]:
        """Swarm B's frames to record and its overrides (none without B): the live B's, or those of
        the replay shown (the lock held)."""
        if self.replaying is not None:
            return list(self.timeline.twin_frames), self.replaying.twin
        if self.compare is None:
            return [], None
        with self.compare.b.lock:
            return list(self.compare.b.history.frames), dict(self.compare.overrides)

    # ------------------------------------------------------------------ history
    def clock(self) -> float:
        """Time since reset. Equals the engine's ``k·Δt`` until Δt is changed mid-run; after that
        it keeps counting from where it was, so trails and plots never jump back in time."""
        return self._t0 + (self.k - self._k0) * self.driver.dt()

    def _metrics(self, info: Any) -> dict[str, float]:
        """Run 0's metric columns now, as ``shoal run`` writes them (``t`` the session's clock),
        then the kind's own (``driver.metrics``)."""
        table = metric_table(self.sim.state, info, self.clock())
        row = {name: float(v[0]) for name, v in table.items() if name not in ("run", "step")}
        return {**row, **self.driver.metrics()}

    def _record(self, info: Any) -> None:
        """Record the robots and the metrics (``info`` of the step just taken; None at a start)."""
        row = self._metrics(info if info is not None else self.sim.info())
        self.history.record(self.driver.frame(row["t"]), tuple(row.values()))

    def metric_arrays(self) -> dict[str, np.ndarray]:
        """The recorded metrics as columns: ``t``, ``best_fitness``, ``max_speed``, ``mean_speed``
        and the engine's own (``Info.columns()``)."""
        with self.lock:
            return self.history.metric_arrays()

    def trails(self, max_trails: int = TRAIL_LIMITS[0], max_trail_points: int = TRAIL_LIMITS[1]) -> Trails:
        """Trails (M, L, d ≤ 3) of the last ``view.trail_seconds``, ending at the robots."""
        with self.lock:
            return self.history.trails(self.clock(), self.scenario.view.trail_seconds, max_trails, max_trail_points)

    def readout(self) -> dict[str, float]:
        """The kind's numbers for the status line and the readouts."""
        with self.lock:
            return self.driver.readout()

    # ------------------------------------------------------------------ what the view shows
    def snapshot(self, max_trails: int = TRAIL_LIMITS[0], max_trail_points: int = TRAIL_LIMITS[1]) -> Snapshot:
        """What the arena draws now: robots, bests, trails of the last ``view.trail_seconds``, the
        kind's extras."""
        with self.lock:
            s = self.sim.state
            selected = min(self.selected_robot, self.robots - 1)
            return Snapshot(scenario=self.scenario, k=s.k, t=self.clock(), x=s.x[0].copy(),
                            heading=s.heading[0].copy(), status=s.status[0].copy(),
                            trails=self.trails(max_trails, max_trail_points), revision=self.revision,
                            selected=selected, twin=self.twin_view(), **self.driver.snapshot(selected))

    def shown_snapshot(self) -> Snapshot:
        """The live snapshot, or (scrubbing or replaying) the recorded frame at the cursor: its
        robots and trails; bests, beliefs and the kind's live overlays are not recorded."""
        with self.lock:
            if self.timeline.live:
                return self.snapshot()
            i = self.timeline.shown_index()
            f = self.history.frames[i]
            snap = self.snapshot()
            trails = self.history.trails(f.t, self.scenario.view.trail_seconds, *TRAIL_LIMITS, upto=i)
            return dataclasses.replace(
                snap, k=f.k, t=f.t, x=f.x, heading=f.heading, status=f.status, trails=trails,
                live=False, y=None, yg=None, ghosts=None, selected=min(snap.selected, len(f.x) - 1),
                extras={**snap.extras, **self.driver.recorded(f)})

    def shown_metrics(self, n: int) -> tuple[dict[str, np.ndarray], tuple[float, float]]:
        """The last ``n`` metric rows up to the time shown, and the time span of all ``n`` (the x range)."""
        with self.lock:
            return self.timeline.shown_metrics(n)

    # ------------------------------------------------------------------ timeline
    def timeline_span(self) -> tuple[int, int, int]:
        """(first, last, shown) recorded step numbers."""
        with self.lock:
            return self.timeline.span()

    def shown_frame(self) -> Frame:
        with self.lock:
            return self.timeline.shown_frame()

    def scrub(self, k: int) -> int:
        """Pause and show the recorded frame nearest step ``k``; returns its step."""
        with self.lock:
            self.playing = False
            shown = self.timeline.scrub(k)
            self.revision += 1
            return shown

    def recording(self) -> Recording:
        """The recorded history (frames, the scene as it was at each, metrics, swarm B's frames)
        with the preset and seed that made it."""
        with self.lock:
            frames = list(self.history.frames)
            metrics = self.history.metric_table()
            shown = self.replaying
            version, edits = (shown.shoal, shown.live_edits) if shown else (shoal.__version__, self.live_edits)
            b_frames, overrides = self._twin_record()
            b = {f.k: f for f in b_frames}
            twins = [(b[f.k].x, b[f.k].status) if f.k in b else None for f in frames]
            meta = replay.make_meta(shoal=version, preset=self.scenario.model_dump(mode="json"),
                                    name=self.scenario.name, seed=int(self.scenario.sim.seed), kind=self.kind.name,
                                    metrics=self.history.names, live_edits=edits,
                                    twin=overrides if any(tw is not None for tw in twins) else None)
        return replay.from_frames(meta, [f.k for f in frames], [f.t for f in frames], [f.x for f in frames],
                                  [f.heading for f in frames], [f.status for f in frames], metrics, twins=twins,
                                  scenes=[f.scene for f in frames])

    def export_replay(self) -> bytes:
        return replay.to_bytes(self.recording())

    def check_replay(self, rec: Recording) -> None:
        """Refuse a recording this session cannot show (raises :class:`ReplayError`, or
        :class:`PresetError` naming B's field for overrides of swarm B the preset cannot take,
        or a frame of more robots than a tab of this kind may show)."""
        d, expect = rec.x.shape[1], self.history.frames[-1].x.shape[-1]
        if d != expect:
            raise replay.ReplayError([f"x: positions have {d} columns but the preset's robots move in {expect}-D"])
        twin = twin_scenario(self.scenario, rec.twin_overrides) if rec.twin_overrides is not None else None
        check_recording(rec, self.scenario, twin)

    def enter_replay(self, rec: Recording, check: tuple[bool | None, str]) -> None:
        """Show ``rec`` (already checked against this session's scenario) instead of the engine."""
        self.check_replay(rec)
        with self.lock:
            self.playing = False
            self.compare = None
            self._share_budget(None, replay_twin=rec.twin_overrides is not None)
            self.timeline.load(rec, check, metrics_match=rec.metric_names == self.history.names)
            self.revision += 1

    def leave_replay(self, play: bool = False) -> None:
        """Back to a live run of the scene's preset from step 0 (``play``: playing it)."""
        with self.lock:
            if self.replaying is not None:
                self._share_budget(None)
                self.restart(self.scenario.sim.seed)
                self.revision += 1
                if play:
                    self.playing = True

    # ------------------------------------------------------------------ export
    def trajectory_rows(self) -> np.ndarray:
        """Rows ``run,step,t,robot,x,y,heading,vx,vy,status`` of the buffered history (run 0)."""
        with self.lock:
            return self.history.rows()

    def export_csv(self) -> bytes:
        buf = _io.StringIO()
        buf.write(trajectory_header(2) + "\n")
        write_trajectory(buf, self.trajectory_rows())
        return buf.getvalue().encode()

    def export_json(self) -> bytes:
        """The run as JSON: the preset as the user built it (:meth:`kept_scenario`, what *Download
        preset* writes; :class:`PresetError` if it cannot hold the edits), seed, version, the kind's
        entries and the trajectories."""
        with self.lock:
            preset = self.kept_scenario().model_dump(mode="json")
            seed = self.sim.seed
            extra = self.driver.export_extra()
        rows = self.trajectory_rows()
        ints = {"run", "step", "robot", "status"}
        trajectories = [
            {c: (int(v) if c in ints else float(v)) for c, v in zip(TRAJECTORY_COLUMNS, row)} for row in rows
        ]
        doc = {"preset": preset, "seed": seed, "version": shoal.__version__, **extra,
               "trajectories": trajectories}
        return json.dumps(doc, separators=(",", ":")).encode()

    def kept_scenario(self) -> Scenario:
        """The scenario with the hand edits of the running scene in its fields (``Driver.kept``)."""
        with self.lock:
            return self.driver.kept(self.scenario)

    def preset_toml(self) -> bytes:
        """The preset a user downloads: the scenario with the hand edits kept."""
        return presets_io.to_toml(self.kept_scenario()).encode()
