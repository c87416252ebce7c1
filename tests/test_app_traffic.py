"""What a page is sent to draw: the stage it renders every frame and the scene updates while a
run plays, read off viser's websocket protocol as a page receives it (``viser_wire``).

A software-rendered page (no GPU) spends its main thread on every frame it renders, and it
renders continuously while updates arrive: what each frame draws is what costs.
"""

from __future__ import annotations

from browser.browser_helpers import wait_until  # noqa: E402  (tests/ is on sys.path)
from viser_wire import WireClient


def test_the_lights_cast_no_shadow(server):
    """Nothing in a flat arena casts a shadow: the page gets the default lights without the
    three cascaded shadow maps viser's lights draw and the ground grid samples otherwise."""
    c = WireClient(server.port, decode=True)
    try:
        wait_until(lambda: "EnableLightsMessage" in c.last, what="the lights")
        lights = c.last["EnableLightsMessage"]
        assert lights["enabled"] is True
        assert lights["cast_shadow"] is False
    finally:
        c.close()
