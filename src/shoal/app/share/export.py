"""Exported pages of a run: from a preset and seed (headless), from recordings, or from a
session's recorded history (the app's *Share*)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any, Callable, Iterable

import shoal
from shoal.engine.core.atomic import atomic_write_text
from shoal.presets import io as presets_io
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

from ..limits import scene_kind
from ..replay import Recording
from ..session.snapshot import Snapshot
from ..session.twin import twin_scenario
from . import draw, page
from .frames import MAX_FRAMES, FramePlan, frame_budget, plan, run_plan, seconds_per_frame


def _page(scenario: Scenario, frames: Iterable[Snapshot], info: page.PageInfo) -> str:
    stem = presets_io.file_stem(scenario.name)
    with page.recording_scene() as (scene, serializer):
        view = draw.new_view(scenario, scene)
        label = page.step_label(scene)
        legend: dict = {}  # what any frame showed, in the order the view lists it
        for frame in frames:
            draw.draw_frame(view, frame)
            legend.update(dict.fromkeys(view.legend()))
            label.text = page.step_text(frame.k, frame.t)
            serializer.insert_sleep(info.seconds_per_frame)
        return page.to_html(serializer, dataclasses.replace(info, legend=tuple(legend)), stem)


def _info(scenario: Scenario, fp: FramePlan, *, origin: str, shoal_version: str, max_frames: int, robots: int,
          live_edits: int = 0, twin: Scenario | None = None, overrides: dict[str, Any] | None = None) -> page.PageInfo:
    return page.PageInfo(
        name=scenario.name, seed=int(scenario.sim.seed), shoal=shoal_version, exported_by=shoal.__version__,
        kind=scene_kind(scenario), origin=origin, first=fp.first, last=fp.last, stride=fp.stride, frames=fp.frames,
        max_frames=max_frames, robots=robots, seconds_per_frame=seconds_per_frame(scenario.view.steps_per_second),
        app_steps_per_second=float(scenario.view.steps_per_second),
        preset=scenario.model_dump(mode="json"), preset_toml=presets_io.to_toml(scenario), live_edits=live_edits,
        twin_overrides=dict(overrides or {}), twin_toml=None if twin is None else presets_io.to_toml(twin))


def preset_html(scenario: Scenario, *, overrides: dict[str, Any] | None = None, max_frames: int = MAX_FRAMES,
                on_steps: Callable[[int], None] | None = None) -> str:
    """The page of a seeded run of ``scenario`` (its ``sim.seed``, ``sim.steps`` steps), drawn
    live as the app draws it; with ``overrides`` also swarm B (Compare). Raises
    :class:`~shoal.presets.io.PresetError` for a scene the app cannot show."""
    session = draw.new_session(scenario)
    if overrides:
        session.enable_compare(overrides)
    twin = session.twin.scenario if session.twin is not None else None
    robots = scenario.sim.robots + (twin.sim.robots if twin is not None else 0)
    limit = frame_budget(robots, max_frames)
    fp = run_plan(scenario.sim.steps, limit)
    info = _info(scenario, fp, origin="seeded run", shoal_version=shoal.__version__, max_frames=limit,
                 robots=robots, twin=twin, overrides=overrides)
    return _page(scenario, draw.run_frames(session, fp, on_steps), info)


def recording_html(rec: Recording, max_frames: int = MAX_FRAMES, kept: Scenario | None = None) -> str:
    """The page of a recording (swarm B's frames too when Compare ran), as the app's timeline
    shows it; its preset to download is ``kept`` (the preset with the hand edits, as Download
    preset writes it) when given, else the recording's. Raises
    :class:`~shoal.presets.io.PresetError` or :class:`~shoal.app.replay.ReplayError` for a
    recording the app could not show."""
    a = draw.replay_session(rec)
    b_n, b_x, _ = rec.twin_rows
    overrides = rec.twin_overrides if len(b_x) else None
    twin = twin_scenario(a.scenario, overrides) if overrides is not None else None
    robots = int(rec.n.max()) + int(b_n.max())
    limit = frame_budget(robots, max_frames)
    fp = plan(rec.k, limit)
    info = _info(a.scenario, fp, origin="recorded history", shoal_version=str(rec.meta["shoal"]),
                 max_frames=limit, robots=robots, live_edits=int(rec.meta["live_edits"]), twin=twin,
                 overrides=overrides)
    if kept is not None:
        info = dataclasses.replace(info, preset=kept.model_dump(mode="json"), preset_toml=presets_io.to_toml(kept))
    return _page(a.scenario, draw.recorded_frames(a, fp), info)


def session_html(session: Any, max_frames: int = MAX_FRAMES) -> bytes:
    """The page of a session's recorded history (swarm B's too when Compare is on, or in the
    replay shown), as UTF-8. Its preset is the one Download preset writes, hand edits kept
    (a replay shown keeps its file's preset; edits a preset cannot hold, such as an obstacle
    in the start box, stay in the frames only, as in a replay)."""
    kept = None
    if not session.replaying:
        try:
            kept = session.kept_scenario()
        except PresetError:
            kept = None
    return recording_html(session.recording(), max_frames, kept).encode("utf-8")


def write_html(path: Path | str, text: str) -> Path:
    """Write a page completely or not at all."""
    atomic_write_text(path, text)
    return Path(path)
