"""The Replay folder of every panel: a timeline over the recorded steps, a badge while a
loaded replay is shown, and the Export replay / Load replay / Share buttons.

Dragging the timeline pauses and shows the recorded frame of that step (robots, trails up
to then, the plots cut there); Play carries on from the live end. *Load replay* reads a
file from *Export replay* (checked by :func:`replay.from_bytes`; a bad one is refused with
a red notification and changes nothing), builds the scene from the preset inside it, checks
that a fresh run of that preset and seed reproduces its first steps, and shows it. *Share*
sends the recorded steps (swarm B's too) as one web page that plays in any browser
(:mod:`.share`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from shoal.presets import io as presets_io
from shoal.presets.io import PresetError

from . import replay, share
from .replay import ReplayError
from .timeline import verify_replay

if TYPE_CHECKING:
    from .panel_base import PanelsBase


class ReplayGui:
    """The handles of the Replay folder, wired to ``panels.session``."""

    def __init__(self, panels: PanelsBase) -> None:
        self.panels = panels
        gui = panels.gui
        with gui.add_folder("Replay") as self.folder:
            self.badge = gui.add_markdown("", visible=False)
            self.timeline = gui.add_slider(
                "timeline [step]", min=0, max=1, step=1, initial_value=0,
                hint="drag to see a recorded step (pauses); Play carries on from the live end")
            self.where = gui.add_markdown("")
            self.export = gui.add_button("Export replay", hint="the recorded steps, preset and seed as one .npz file")
            self.upload = gui.add_upload_button(
                "Load replay", hint=f"a .npz from Export replay, at most {replay.MAX_REPLAY_BYTES // 2**20} MiB")
            self.share = gui.add_button(
                "Share", hint="the recorded steps as one web page (.html) that plays in any browser, no install")
        panels.top.append(self.folder)
        self._wire()

    @property
    def session(self) -> Any:
        return self.panels.session

    def _wire(self) -> None:
        @self.timeline.on_update
        def _(event: Any) -> None:
            if not self.panels._syncing:
                self.session.scrub(int(round(self.timeline.value)))
                self.refresh()

        @self.export.on_click
        def _(event: Any) -> None:
            self.panels.send_file(f"{self.panels._stem()}-replay.npz", self.session.export_replay())

        @self.share.on_click
        def _(event: Any) -> None:
            try:
                page = share.session_html(self.session)
            except (PresetError, ReplayError, share.Busy) as err:
                self.panels._refuse(err, "share")
                return
            self.panels.send_file(f"{self.panels._stem()}-run.html", page)

        @self.upload.on_upload
        def _(event: Any) -> None:
            f = event.target.value
            self.load(f.name, f.content)

    # ------------------------------------------------------------------ loading
    def load(self, filename: str, content: bytes) -> bool:
        """Check a replay file and show it; a bad one is refused and nothing changes."""
        p = self.panels
        try:
            rec = replay.from_bytes(content, filename)
            try:
                scenario = presets_io.validate(rec.meta["preset"])
            except PresetError as err:
                raise PresetError([f"preset: {m}" for m in err.messages]) from None
            from .tab import kind_for  # the tab module imports the panels

            fresh = kind_for(scenario).session(scenario)
            fresh.check_replay(rec)
            try:
                check = verify_replay(fresh, rec)
            except Exception as err:  # the check must never keep a good file out
                check = (None, f"not checked ({type(err).__name__}: {err})")
            p.session.pause()
            session = p.replace(scenario) if p.replace is not None else p.session
            if p.replace is None:
                session.load_scenario(scenario)
                p.sync_from_scenario()
            session.enter_replay(rec, check)
        except (PresetError, ReplayError) as err:
            p._refuse(err, f"replay {filename}")
            return False
        color = {True: "green", False: "yellow", None: "blue"}[check[0]]
        p.notify(f"Replay of {rec.name}, seed {rec.seed}", f"{rec.frames} steps · {check[1]}", color)
        return True

    # ------------------------------------------------------------------ readouts
    def refresh(self) -> None:
        """Timeline range and position, and the badge (the caller throttles this)."""
        p = self.panels
        if p.removed:
            return
        s = self.session
        first, last, shown = s.timeline()
        with s.lock:
            t = s.shown_frame().t
            info, live = s.replaying, s.cursor is None and s.replaying is None
        with p._sync():
            hi = max(last, first + 1)
            if (self.timeline.min, self.timeline.max) != (first, hi):
                self.timeline.min, self.timeline.max = first, hi
            p._set(self.timeline, shown)
        state = "live" if live else ("replay" if info is not None else "recorded")
        self.where.content = f"{state}: step {shown} · t = {t:.4g} · recorded steps {first}–{last}"
        if info is None:
            self.badge.visible = False
            return
        mark = {True: "✓", False: "✗", None: "·"}[info.verified]
        edits = f" · {info.live_edits} live edit(s) while it ran" if info.live_edits else ""
        self.badge.content = (f"**Replay of {info.name}, seed {info.seed}** (shoal {info.shoal}){edits}  \n"
                              f"{mark} {info.check} · Reset runs the preset live")
        self.badge.visible = True
