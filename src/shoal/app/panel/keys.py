"""Keyboard shortcuts of the page: space = Play/Pause, → = Step, r = Reset.

viser passes no key events to Python, but it runs a script the server sends
(``RunJavascriptMessage``, the way it loads plotly). :func:`install_keys` sends a small one
that turns a key into a click on the header's own playback button, so a key takes the same
path as a click (and a hostile client gains nothing it could not send as a click). Keys typed
into a text or number box, a dropdown or a slider, or with Ctrl/Alt/⌘, are left alone.
"""

from __future__ import annotations

import json
from typing import Any

from viser import _messages

PLAYING = "▶ playing"  # the status line's words while a run plays (the script reads them)
KEYS = {" ": "Play/Pause", "ArrowRight": "Step", "r": "Reset", "R": "Reset"}

KEYS_JS = """
(() => {
  if (window.__shoalKeys) return;
  window.__shoalKeys = true;
  const KEYS = %(keys)s;
  const button = (name) => [...document.querySelectorAll("button")].find((b) => b.textContent.trim() === name);
  const playing = () => [...document.querySelectorAll("p")].some((p) => p.textContent.includes(%(playing)s));
  const typing = (t) => t instanceof Element && (t.isContentEditable
    || ["INPUT", "TEXTAREA", "SELECT"].includes(t.tagName) || ["slider", "combobox"].includes(t.getAttribute("role")));
  document.addEventListener("keydown", (e) => {
    if (e.ctrlKey || e.metaKey || e.altKey || e.repeat || !(e.key in KEYS) || typing(e.target)) return;
    const name = KEYS[e.key] === "Play/Pause" ? (playing() ? "Pause" : "Play") : KEYS[e.key];
    const b = button(name);
    if (!b) return;
    e.preventDefault();
    if (e.target instanceof HTMLElement && e.target.tagName === "BUTTON") e.target.blur();  // no second click on keyup
    b.click();
  }, true);
})();
"""


def keys_script() -> str:
    return KEYS_JS % {"keys": json.dumps(KEYS), "playing": json.dumps(PLAYING)}


def install_keys(gui: Any) -> None:
    """Send the shortcuts' script to the page of ``gui`` (a client's ``GuiApi``)."""
    gui._websock_interface.queue_message(_messages.RunJavascriptMessage(source=keys_script()))
