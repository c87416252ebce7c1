"""An exported run as one HTML page: viser's own static client with the recorded scene in it
(``StateSerializer.as_html``), and a panel that names the run.

The arena is drawn on a private viser server (loopback, a free port, every request refused)
whose scene serializer records every message; a pause between kept steps gives viser's
player its timeline (play/pause, a scrub bar, 0.5×–8×). The panel (preset, seed, versions,
frames kept, the preset as TOML to download) is plain, escaped HTML beside the client's root;
the same facts are in a JSON block (``#shoal-run-data``) for programs. On a computer without
a GPU, viser's toast about software WebGL would cover the panel: a small script closes it and
the panel says so in one line (:data:`SOFTWARE_JS`).
"""

from __future__ import annotations

import contextlib
import html
import io
import json
import threading
import urllib.parse
from dataclasses import dataclass, field
from typing import Any, Iterator

from ..origin_guard import Closed, guarded_viser
from ..panel.view_row import legend_html
from ..session.twin import literal
from ..view.camera import VIEW_HALF, top_view
from ..view.layers import LegendEntry
from .frames import MAX_FRAMES, MAX_ROBOT_FRAMES

_LOCK = threading.Lock()  # one export at a time per process: CPU, and stdout is swapped while viser prints
_QUEUE = threading.BoundedSemaphore(2)  # exports running or waiting: a shared server's callback threads stay free
STEP_LABEL = "/shoal_step"


class Busy(RuntimeError):
    """Another export is running and one more is waiting (``messages`` as a preset error's)."""

    def __init__(self) -> None:
        self.messages = ["another page is being made on this server; try again in a moment"]
        super().__init__(self.messages[0])


@contextlib.contextmanager
def _quiet() -> Iterator[None]:
    """viser prints a banner on start and a line on stop, even with ``verbose=False``. The swap of
    ``sys.stdout`` is process-wide: only under ``_LOCK``, for the moments viser prints."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield


@contextlib.contextmanager
def recording_scene() -> Iterator[tuple[Any, Any]]:
    """(scene, serializer) of a private viser server whose camera looks straight down on the
    arena as the app's does; the server is stopped on the way out. It refuses every request
    (:class:`~shoal.app.origin_guard.Closed`): while it lives (seconds, or the whole run of an
    export), no page and no rebinding name can read the scene. One export runs at a time and
    one more may wait; a third is refused (:class:`Busy`)."""
    if not _QUEUE.acquire(blocking=False):
        raise Busy()
    try:
        with _LOCK:
            with _quiet():
                server = guarded_viser("127.0.0.1", 0, Closed())
            try:
                top_view(server)
                yield server.scene, server.get_scene_serializer()
            finally:
                with _quiet():
                    server.stop()
    finally:
        _QUEUE.release()


def step_label(scene: Any) -> Any:
    """A label above the arena's top-left corner that the exporter sets to each frame's step."""
    return scene.add_label(STEP_LABEL, "", position=(-VIEW_HALF, VIEW_HALF + 0.25, 0.0), anchor="bottom-left",
                           font_screen_scale=1.25)


def step_text(k: int, t: float) -> str:
    return f"step {k} · t = {t:.4g} s"


@dataclass(frozen=True)
class PageInfo:
    """What the page says about the run it plays."""

    name: str
    seed: int
    shoal: str  # the version that ran it
    exported_by: str  # the version that wrote the page
    kind: str  # the kind of scene, in words
    origin: str  # "seeded run" or "recorded history"
    first: int
    last: int
    stride: int
    frames: int
    max_frames: int  # the budget of this page (:func:`~.frames.frame_budget`)
    robots: int  # the most robots in a frame (swarm B's included)
    seconds_per_frame: float  # the page's clock between two frames
    app_steps_per_second: float  # the app's playback rate the run was shown at
    preset: dict[str, Any]
    preset_toml: str
    live_edits: int = 0
    twin_overrides: dict[str, Any] = field(default_factory=dict)
    twin_toml: str | None = None
    legend: tuple[LegendEntry, ...] = ()  # the glyphs the page draws

    def data(self) -> dict[str, Any]:
        run = {k: getattr(self, k) for k in ("name", "seed", "shoal", "kind", "origin", "first", "last", "stride",
                                             "frames", "max_frames", "robots", "seconds_per_frame", "live_edits")}
        run["seconds"] = self.seconds
        twin = None if self.twin_toml is None else {"overrides": self.twin_overrides}
        return {"exported_by": f"shoal {self.exported_by}", "run": run, "preset": self.preset, "twin": twin}

    @property
    def fps(self) -> float:
        """Frames a second at 1×."""
        return 1.0 / self.seconds_per_frame

    @property
    def seconds(self) -> float:
        """The page's clock at the end of its last frame, at 1× (every frame holds ``seconds_per_frame``)."""
        return self.frames * self.seconds_per_frame

    def pace(self) -> str:
        """The page's steps a second against the app's, in words."""
        ratio = self.stride * self.fps / self.app_steps_per_second
        return "the app's pace" if abs(ratio - 1.0) < 1e-9 else f"{ratio:.3g}× the app's pace"


STYLE = """
#shoal-run{position:fixed;top:12px;left:12px;z-index:20;max-width:17rem;max-height:calc(100vh - 90px);
 overflow:auto;background:rgba(255,255,255,.94);border:1px solid #d5d7de;border-radius:6px;
 box-shadow:0 2px 10px rgba(0,0,0,.12);font:13px/1.45 system-ui,-apple-system,"Segoe UI",sans-serif;
 color:#222;padding:.45rem .7rem}
#shoal-run summary{cursor:pointer;font-weight:600}
#shoal-run table{border-collapse:collapse;margin:.35rem 0}
#shoal-run td{padding:0 .6rem 0 0;vertical-align:top}
#shoal-run td:first-child{color:#666;white-space:nowrap}
#shoal-run p{margin:.35rem 0}
#shoal-run details details{margin-top:.3rem}
#shoal-run pre{font-size:11px;max-height:16rem;overflow:auto;background:#f5f6f8;padding:.3rem}
#shoal-run code{font-size:12px}
#shoal-run .twin{color:#006fa8;font-weight:600}
#shoal-run .legend{margin:.3rem 0}
"""


SOFTWARE_NOTE = ("Drawn without a GPU (software WebGL): the page may skip frames, its clock keeps time.")
SOFTWARE_JS = """
(() => {
  const TITLE = "Software WebGL rendering detected";
  const close = () => {
    for (const n of document.querySelectorAll(".mantine-Notification-root")) {
      if (!n.textContent.includes(TITLE)) continue;
      const button = n.querySelector("button");
      if (button) button.click();
      const note = document.getElementById("shoal-software");
      if (note) note.hidden = false;
    }
  };
  new MutationObserver(close).observe(document.body, {childList: true, subtree: true});
})();
"""


def _download(name: str, text: str, label: str) -> str:
    href = "data:application/toml;charset=utf-8," + urllib.parse.quote(text)
    return f'<a download="{html.escape(name)}" href="{html.escape(href)}">{html.escape(label)}</a>'


def _ordinal(n: int) -> str:
    suffix = "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"{n}{suffix}"


def panel(info: PageInfo, file_stem: str) -> str:
    """The run's panel as HTML (every value escaped): the facts at a glance, the rest folded."""
    e = html.escape
    rows = [("preset", e(info.name)), ("seed", str(info.seed)), ("scene", e(info.kind)),
            ("steps", f"{info.first}–{info.last}"), ("ran with", f"shoal {e(info.shoal)}")]
    table = "".join(f"<tr><td>{k}</td><td>{v}</td></tr>" for k, v in rows)
    every = "every step" if info.stride == 1 else f"every {_ordinal(info.stride)} step and the last"
    budget = f" (for {info.robots} robots: {info.max_frames} frames)" if info.max_frames < MAX_FRAMES else ""
    parts = [f"<details open><summary>Shoal · {e(info.name)}, seed {info.seed}</summary><table>{table}</table>"]
    if info.legend:
        parts.append(f'<p class="legend">{legend_html(info.legend)}</p>')
    if info.twin_toml is not None:
        lines = ", ".join(f"<code>{e(k)}={e(literal(v))}</code>" for k, v in info.twin_overrides.items())
        parts.append(f'<p><span class="twin">Blue squares: swarm B</span>, the same preset and seed with '
                     f'{lines or "no change"}'
                     f" ({_download(f'{file_stem}-B.toml', info.twin_toml, 'its preset')}).</p>")
    if info.live_edits:
        parts.append(f"<p>Changed {info.live_edits} time(s) while it ran: a fresh run of this preset and seed "
                     "differs from it.</p>")
    parts.append(f'<p id="shoal-software" hidden><small>{SOFTWARE_NOTE}</small></p>')
    parts.append(f"<p>{_download(f'{file_stem}.toml', info.preset_toml, 'Download the preset (TOML)')}</p>")
    parts.append(
        "<details><summary>About this page</summary>"
        f"<p>{info.frames} frames of a {e(info.origin)} of {info.robots} robots ({every}), steps "
        f"{info.first}–{info.last}. At 1× the page plays {info.fps:.3g} frames a second, {info.pace()}: its clock, "
        f"the number beside ▶, runs from 0 to {info.seconds:.4g} s, while the label above the arena gives each "
        "frame's step and the run's time t. A slow computer may skip frames, never the clock.</p>"
        f"<p>A page keeps at most {MAX_FRAMES} frames and {MAX_ROBOT_FRAMES:,} robot positions{budget}, so that it "
        "stays a few MB.</p>"
        "<p>▶/❚❚ plays and pauses (or the space bar), the bar scrubs, the menu sets the speed; drag to turn the "
        "view, scroll to zoom.</p>"
        f"<p>Run it yourself: <code>shoal run {e(file_stem)}.toml --seed {info.seed}</code>. Page by shoal "
        f"{e(info.exported_by)} with viser's player; nothing to install, no server.</p>"
        f"<details><summary>Preset</summary><pre>{e(info.preset_toml)}</pre></details></details>")
    return '<div id="shoal-run">' + "".join(parts) + "</details></div>"


def _json_script(data: dict[str, Any]) -> str:
    text = json.dumps(data, ensure_ascii=False, separators=(",", ":"))
    text = text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")  # never ends the script
    return f'<script type="application/json" id="shoal-run-data">{text}</script>'


def to_html(serializer: Any, info: PageInfo, file_stem: str) -> str:
    """viser's standalone page of the recorded scene with the run's title, panel and data."""
    page = serializer.as_html()
    title = f"{info.name}, seed {info.seed} · Shoal"
    head = f"<title>{html.escape(title)}</title><style>{STYLE}</style>"
    if "<title>Viser</title>" in page:
        page = page.replace("<title>Viser</title>", head, 1)
    else:
        page = page.replace("</head>", head + "</head>", 1)
    body = panel(info, file_stem) + _json_script(info.data()) + f"<script>{SOFTWARE_JS}</script>"
    cut = page.rindex("</body>")
    return page[:cut] + body + page[cut:]
