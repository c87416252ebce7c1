"""Check a control's value from the page before viser takes it.

Viser casts an incoming value to the type of the control's current value (``int("abc")``,
``int(nan)``, ``float(None)``, ``str([1])``) on its event loop. A value that cannot be cast
raises there and is lost without a word ("Task exception was never retrieved"); one that can
(``int(1.5)`` is 1, any string for a dropdown) reaches the app as if the user had picked it.
A page only sends values its controls can hold, but anything that speaks the websocket
protocol can send any value. So every ``GuiUpdateMessage`` of a tab passes :func:`problem`
first: a value of the wrong kind, not finite, not whole for a whole-number control, not among
a dropdown's options, outside a slider's or number box's own range (its ``min`` and ``max``:
what its page could send), or an update of anything but the value is refused with a red
message naming the control, and the control shows the value in force again. A number box
without a bound leaves that end to the app, which names the preset field; a number no control
could hold (beyond :data:`MAX_MAGNITUDE`, e.g. 1e308, which viser would cast to a 309-digit
integer that msgpack cannot send back) is refused here.

It replaces viser's handler of these messages on the tab's ``GuiApi`` (viser 1.x:
``GuiApi._handle_gui_updates``) with one that checks and then calls it. If a viser version
keeps it elsewhere, :func:`guard_inputs` installs nothing and says so.
"""

from __future__ import annotations

import math
from typing import Any, Callable

from viser import _messages

from shoal.presets.io import short

MAX_TEXT = 10_000  # characters of a text control's value
MAX_MAGNITUDE = 2.0**63  # the largest number a control takes (an int64 seed is the largest any holds)
Refuse = Callable[[str, str], None]  # (title, body) of the red message


def _number(value: Any, whole: bool, low: Any = None, high: Any = None) -> str | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return "expected a whole number" if whole else "expected a number"
    if whole and isinstance(value, float) and not value.is_integer():  # NaN and ±inf are not either
        return "expected a whole number"
    if isinstance(value, float) and not math.isfinite(value):
        return "expected a finite number"
    if _bound(low) is not None and value < low:
        return f"less than its least value {low:g}"
    if _bound(high) is not None and value > high:
        return f"more than its largest value {high:g}"
    return f"beyond ±{MAX_MAGNITUDE:.3g}" if abs(value) > MAX_MAGNITUDE else None


def _bound(end: Any) -> float | None:
    """A control's ``min`` or ``max``, if it has a finite one."""
    ok = isinstance(end, (int, float)) and not isinstance(end, bool) and math.isfinite(end)
    return float(end) if ok else None


def problem(current: Any, value: Any, options: tuple[str, ...] | None = None, low: Any = None,
            high: Any = None) -> str | None:
    """Why ``value`` cannot replace a control's ``current`` value (None: it can); ``low`` and
    ``high``: a number control's own range."""
    if isinstance(current, bool):
        return None if isinstance(value, bool) else "expected true or false"
    if isinstance(current, (int, float)):
        return _number(value, isinstance(current, int), low, high)
    if isinstance(current, str):
        if not isinstance(value, str):
            return "expected text"
        if options is not None and value not in options:
            return "not one of the choices"
        return f"longer than {MAX_TEXT} characters" if len(value) > MAX_TEXT else None
    if isinstance(current, tuple):
        if not isinstance(value, (list, tuple)) or len(value) != len(current):
            return f"expected {len(current)} values"
        return next((p for c, v in zip(current, value) if (p := problem(c, v)) is not None), None)
    return "this control takes no value from the page"


def guard_inputs(gui: Any, refuse: Refuse) -> bool:
    """On ``gui`` (a client's ``GuiApi``), refuse malformed control values with ``refuse``.
    Returns whether the guard could be installed."""
    interface = getattr(gui, "_websock_interface", None)
    handles = getattr(gui, "_gui_input_handle_from_uuid", None)
    inner = getattr(gui, "_handle_gui_updates", None)
    registered = getattr(interface, "_incoming_handlers", {}).get(_messages.GuiUpdateMessage, [])
    if interface is None or not isinstance(handles, dict) or inner is None or inner not in registered:
        return False

    async def checked(client_id: Any, message: _messages.GuiUpdateMessage) -> None:
        handle = handles.get(message.uuid)
        if handle is None:
            return await inner(client_id, message)  # (viser ignores it)
        updates = message.updates if isinstance(message.updates, dict) else {}
        value = updates.get("value")
        why = ("only a control's value can be set" if set(updates) != {"value"}
               else problem(handle.value, value, getattr(handle, "options", None), getattr(handle, "min", None),
                            getattr(handle, "max", None)))
        if why is None:
            return await inner(client_id, message)
        label = str(getattr(handle, "label", "") or "control")
        refuse(f"Refused: {label} = {short(value)}", f"{label}: {why} (got {short(value)})")
        interface.queue_message(_messages.GuiUpdateMessage(message.uuid, {"value": handle.value}))

    interface.unregister_handler(_messages.GuiUpdateMessage, inner)
    interface.register_handler(_messages.GuiUpdateMessage, checked)
    return True
