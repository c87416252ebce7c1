"""A tab that leaves gives its memory back; a client cannot park memory in unfinished uploads.

Real websocket clients (``viser_wire.WireClient``) on a real app server: after a tab closes,
its session, simulation, panels, arena, viser client handle, scene nodes and GUI handles are
all collected (weak references die). The resident-memory side (native memory a closed tab
frees goes back to the system) is measured by ``benchmarks/bench_tabs_memory.py``.
"""

from __future__ import annotations

import gc
import weakref
from typing import Any, Iterator

import pytest
from viser._gui_handles import _GuiHandle
from viser._scene_handles import SceneNodeHandle

from shoal.app.server import MAX_PENDING_BYTES, MAX_TRANSFER_BYTES

from browser.browser_helpers import wait_until  # noqa: E402  (tests/ is on sys.path)
from viser_wire import WireClient


def _handles(obj: Any, kind: type, depth: int = 3) -> Iterator[Any]:
    """Instances of ``kind`` among ``obj``'s attributes (and in their lists, dicts and objects)."""
    seen: set[int] = set()
    stack = [(obj, 0)]
    while stack:
        node, level = stack.pop()
        if id(node) in seen or level > depth:
            continue
        seen.add(id(node))
        if isinstance(node, kind):
            yield node
            continue
        if isinstance(node, dict):
            stack += [(v, level + 1) for v in node.values()]
        elif isinstance(node, (list, tuple)):
            stack += [(v, level + 1) for v in node]
        elif hasattr(node, "__dict__") and node.__class__.__module__.startswith("shoal"):
            stack += [(v, level + 1) for v in vars(node).values()]


def _weak_parts(server: Any, cid: int) -> dict[str, weakref.ref]:
    """Weak references to everything of tab ``cid`` that must go with it (none kept strongly here)."""
    tab = server.tabs[cid]
    scene = list(_handles(tab.arena, SceneNodeHandle))
    gui = list(_handles(tab.panels, _GuiHandle))
    assert len(scene) >= 3 and len(gui) >= 15, (len(scene), len(gui))
    parts = {"tab": tab, "session": tab.session, "sim": tab.session.sim, "panels": tab.panels,
             "arena": tab.arena, "client": server.viser.get_clients()[cid],
             **{f"scene node {h.name}": h for h in scene},
             **{f"GUI {type(h).__name__} {i}": h for i, h in enumerate(gui)}}
    return {name: weakref.ref(obj) for name, obj in parts.items()}


@pytest.mark.parametrize("preset", ["default", "course-dvc", "sonar-xb-pso", "slo-walk"])
def test_a_closed_tab_leaves_nothing_behind(preset):
    from shoal.app.server import start_server

    server = start_server(preset, port=0)
    try:
        client = WireClient(server.port, decode=True)
        wait_until(lambda: client.uuid_of("Upload preset") and len(server.tabs) == 1, what="the tab's panels")
        cid = max(server.tabs)
        wait_until(lambda: server.tabs[cid].session.sim.state.k > 5 and server.tabs[cid].arena.drawn_revision > 0,
                   what="the tab playing")
        refs = _weak_parts(server, cid)
        client.close()
        wait_until(lambda: not server.tabs and not server.viser.get_clients(), what="the tab to be forgotten")

        def alive() -> list[str]:
            gc.collect()
            return [name for name, ref in refs.items() if ref() is not None]

        wait_until(lambda: not alive(), timeout=30, what="everything of the closed tab to be collected")
    finally:
        server.stop()


def test_unfinished_uploads_are_capped_per_tab_and_dropped_when_it_leaves(server):
    client = WireClient(server.port, decode=True)
    try:
        wait_until(lambda: client.uuid_of("Upload preset") and len(server.tabs) == 1, what="the upload button")
        cid = max(server.tabs)
        gui = server.viser.get_clients()[cid].gui
        states = gui._current_file_upload_states
        half = b"#" * (512 * 1024)
        for _ in range(200):  # 200 uploads of 1 MiB, each sent half-way: 100 MiB if nothing stopped them
            client.upload("Upload preset", "x.toml", half, parts=2, declared=2 * len(half), send=1)
        client.set_value("seed", 3)  # handled after every message before it
        wait_until(lambda: server.sessions[cid].scenario.sim.seed == 3, what="the messages handled")
        held = sum(max(s["total_bytes"], s["transferred_bytes"]) for s in list(states.values()))
        assert 0 < held <= MAX_PENDING_BYTES + MAX_TRANSFER_BYTES and len(states) < 100
        refusals = [n for n in client.notifications() if "unfinished uploads of this tab" in n[1]]
        assert 1 <= len(refusals) <= 3 and refusals[0][2] == "red"  # said, not 160 times
        ref = weakref.ref(gui)
        del gui
    finally:
        client.close()
    wait_until(lambda: not states, what="the unfinished uploads dropped with the tab")
    wait_until(lambda: (gc.collect(), ref() is None)[1], what="the tab's GUI collected")


def test_a_large_lag_table_is_not_kept_after_its_scene():
    """The waveform sonar's lag tables (cos and sin, K bins × L lags) were cached, 32 of any
    size, for the server's life: a band of 2,000 bins at 1 MHz made 32 MB each. Small ones
    are still kept (a scene reuses its table every tick); a large one goes with its scene."""
    from shoal.engine.acoustics.band import Band
    from shoal.engine.acoustics.receiver import CACHED_PHASES, lag_table

    small = Band(f_c=1000.0, Q=1.5, tbp=100.0, c=1500.0, fs=48_000.0)
    assert lag_table(small, 0.75)[1] is lag_table(small, 0.75)[1]  # kept
    big = Band(f_c=1000.0, Q=1.5, tbp=2000.0, c=1500.0, fs=1_000_000.0)
    lags, cos, sin = lag_table(big, 0.75)
    assert cos.size > CACHED_PHASES and cos.nbytes > 15 * 2**20
    gone = weakref.ref(cos)
    del lags, cos, sin
    gc.collect()
    assert gone() is None, "a large lag table is still referenced (cached)"
