"""The replay part of every panel's *Replay and files* folder: a timeline over the recorded
steps, a badge and a *Run live* button while a loaded replay is shown, and the Export
replay / Load replay / Share buttons.

Dragging the timeline pauses and shows the recorded frame of that step (robots, trails up
to then, the plots cut there); Play carries on from the live end. *Load replay* reads a
file from *Export replay* (checked by :func:`~shoal.app.replay.from_bytes`; a bad one is
refused with a red notification and changes nothing), builds the scene from the preset
inside it, checks that a fresh run of that preset and seed reproduces its first steps, and
shows it from its first step, paused: Play plays it, Reset goes back to its first step,
*Run live* (or a changed control) leaves it for a live run of its preset. *Share* sends the
recorded steps (swarm B's too) as one web page that plays in any browser.
"""

from __future__ import annotations

from typing import Any

from shoal.presets import io as presets_io
from shoal.presets.io import PresetError

from .. import replay
from ..markdown import escape
from ..replay import ReplayError
from ..session.timeline import verify_replay
from .spec import Host


class ReplayFolder:
    """The replay handles (built in the caller's folder; ``badge``, the line that names a loaded
    replay, and ``live``, the button that leaves it, outside it so that they show with the
    folder closed), wired to ``panel.session``."""

    def __init__(self, panel: Host, badge: Any, live: Any) -> None:
        self.panel = panel
        gui = panel.gui
        self.badge, self.live = badge, live
        self.timeline = gui.add_slider(
            "timeline [step]", min=0, max=1, step=1, initial_value=0,
            hint="drag to see a recorded step (pauses); Play carries on from the live end")
        self.where = gui.add_markdown("")
        self.export = gui.add_button(
            "Export replay", hint="the recorded steps (swarm B, obstacles and source as they were), preset and seed "
                                  "as one .npz file")
        self.upload = gui.add_upload_button(
            "Load replay", hint=f"a .npz from Export replay, at most {replay.MAX_REPLAY_BYTES // 2**20} MiB")
        self.share = gui.add_button(
            "Share", hint="the recorded steps as one web page (.html) that plays in any browser, no install",
            visible=panel.services.share is not None)
        self._wire()

    @property
    def session(self) -> Any:
        return self.panel.session

    def _wire(self) -> None:
        @self.timeline.on_update
        def _(event: Any) -> None:
            if not self.panel.syncing:
                self.session.scrub(int(round(self.timeline.value)))
                self.refresh()

        @self.export.on_click
        def _(event: Any) -> None:
            self.panel.send_file(f"{self.panel.stem()}-replay.npz", self.session.export_replay())

        @self.share.on_click
        def _(event: Any) -> None:
            make = self.panel.services.share
            if make is None:
                return
            try:
                page = make(self.session)
            except (PresetError, ReplayError, RuntimeError) as err:  # RuntimeError: share.Busy
                self.panel.refuse(err, "share")
                return
            self.panel.send_file(f"{self.panel.stem()}-run.html", page)

        @self.upload.on_upload
        def _(event: Any) -> None:
            f = event.target.value
            self.load(f.name, f.content)

        @self.live.on_click
        def _(event: Any) -> None:
            self.run_live()

    def run_live(self) -> None:
        """Leave the replay shown for a live run of its preset, playing."""
        p = self.panel
        p.controls += 1
        self.session.leave_replay(play=True)
        p.sync()
        p.refresh_status()
        self.refresh()

    # ------------------------------------------------------------------ loading
    def load(self, filename: str, content: bytes) -> bool:
        """Check a replay file and show it; a bad one is refused and nothing changes."""
        p = self.panel
        try:
            rec = replay.from_bytes(content, filename)
            try:
                scenario = presets_io.validate(rec.meta["preset"])
            except PresetError as err:
                raise PresetError([f"preset: {m}" for m in err.messages]) from None
            fresh = p.services.make_session(scenario)
            fresh.check_replay(rec)
            try:
                check = verify_replay(fresh, rec)
            except Exception as err:  # the check must never keep a good file out
                check = (None, f"not checked ({type(err).__name__}: {err})")
            p.session.pause()
            if p.services.replace is not None:
                session = p.services.replace(scenario)
            else:
                session = p.session
                session.load_scenario(scenario)
                p.sync()
            session.enter_replay(rec, check)
        except (PresetError, ReplayError) as err:
            p.refuse(err, f"replay {filename}")
            return False
        color = {True: "green", False: "yellow", None: "blue"}[check[0]]
        p.notify(f"Replay of {rec.name}, seed {rec.seed}", f"{rec.frames} steps · {check[1]}", color)
        return True

    # ------------------------------------------------------------------ readouts
    def refresh(self) -> None:
        """Timeline range and position, and the badge (the caller throttles this)."""
        p = self.panel
        if p.removed:
            return
        s = self.session
        first, last, shown = s.timeline_span()
        with s.lock:
            t = s.shown_frame().t
            info, live = s.replaying, s.timeline.live
        with p.quietly():
            hi = max(last, first + 1)
            if (self.timeline.min, self.timeline.max) != (first, hi):
                self.timeline.min, self.timeline.max = first, hi
            p.set_quietly(self.timeline, shown)
        state = "live" if live else ("replay" if info is not None else "recorded")
        self.where.content = f"{state}: step {shown:d} · t = {t:.4g} · recorded steps {first:d}–{last:d}"
        if info is None:
            self.badge.visible = self.live.visible = False
            return
        mark = {True: "✓", False: "✗", None: "·"}[info.verified]
        edits = f" · {info.live_edits:d} live edit(s) while it ran" if info.live_edits else ""
        edits += " · with swarm B (blue)" if info.twin is not None else ""
        self.badge.content = (f"**Replay of {escape(info.name)}, seed {info.seed:d}** (shoal {escape(info.shoal)})"
                              f"{edits}  \n{mark} {escape(info.check)} · "
                              "Play plays it, Reset goes back to its first step")
        self.badge.visible = self.live.visible = True
