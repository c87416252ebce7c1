"""Stop an oversized upload while it arrives, not after viser has buffered all of it.

Viser collects every part of an uploaded file in memory and only then calls the upload
button's callback, where the app checks the size (``MAX_UPLOAD_BYTES`` for presets,
``MAX_REPLAY_BYTES`` for replays). A page cannot send more than the file it picked, but
anything that speaks the websocket protocol can declare or send gigabytes, or start a
thousand uploads and never finish them. This guard drops a transfer as soon as its declared
or received size passes a limit (or what it declared), or when the client's unfinished
uploads together would pass ``pending_limit``; it frees the parts already received and
tells the tab why (each kind of refusal at most every few seconds). Viser itself drops a
client's unfinished uploads when it disconnects.

The page's own toast for an upload ("Uploading …", then "File uploaded successfully." as soon
as the bytes are in, before the app has read them) is closed when the upload starts, so the
only message a user sees is the app's verdict (loaded, or refused and why).

It reads viser's bookkeeping of transfers in progress (``GuiApi._current_file_upload_states``,
viser 1.x). If a viser version keeps them elsewhere, :func:`guard_uploads` installs nothing
and says so; the size checks after the upload still hold.
"""

from __future__ import annotations

import time
from typing import Any, Callable

from viser import _messages

Refuse = Callable[[str, str], None]  # (file name, why)
UPLOAD_TOAST = "upload-"  # the page's id of its own upload toast, before the transfer's uuid
QUIET_SECONDS = 3.0  # a refusal within this time of the last one of its kind told is not told again


def _mib(size: int) -> str:
    return f"{size / 2**20:.1f} MiB"


def guard_uploads(gui: Any, limit: int, pending_limit: int, refuse: Refuse) -> bool:
    """On ``gui`` (one client's ``GuiApi``), drop any upload larger than ``limit`` bytes or
    beyond ``pending_limit`` bytes of unfinished uploads, and call ``refuse``. Returns whether
    the guard could be installed."""
    states = getattr(gui, "_current_file_upload_states", None)
    interface = getattr(gui, "_websock_interface", None)
    if not isinstance(states, dict) or interface is None:
        return False
    told: dict[str, float] = {}  # kind of refusal → when last told

    def drop(transfer_uuid: str, kind: str, why: str) -> None:
        state = states.pop(transfer_uuid, None)  # later parts of it are then ignored by viser
        if state is not None and time.monotonic() - told.get(kind, -QUIET_SECONDS) >= QUIET_SECONDS:
            told[kind] = time.monotonic()
            refuse(str(state.get("filename", "")), why)

    def size(state: dict[str, Any]) -> int:
        return max(int(state.get("total_bytes", 0)), int(state.get("transferred_bytes", 0)))

    def on_start(client_id: Any, message: _messages.FileTransferStartUpload) -> None:
        # the page names its toast "upload-<transfer uuid>"; later updates of a closed toast do nothing
        interface.queue_message(_messages.RemoveNotificationMessage(UPLOAD_TOAST + message.transfer_uuid))
        pending = sum(size(s) for s in list(states.values()))  # this one included
        if message.size_bytes > limit:
            drop(message.transfer_uuid, "size",
                 f"{_mib(message.size_bytes)} is more than the {_mib(limit)} an upload may have")
        elif pending > pending_limit:
            drop(message.transfer_uuid, "pending", f"unfinished uploads of this tab would hold {_mib(pending)}, "
                                                   f"more than the {_mib(pending_limit)} allowed; wait for them")

    def on_part(client_id: Any, message: _messages.FileTransferPart) -> None:
        state = states.get(message.transfer_uuid)
        if state is None:
            return
        got = int(state.get("transferred_bytes", 0))
        if got > limit or got > int(state.get("total_bytes", 0)):
            drop(message.transfer_uuid, "sent",
                 f"{_mib(got)} sent, more than it declared or than the {_mib(limit)} an upload may have")

    # Registered after viser's own handlers, so these run once viser has recorded the message.
    interface.register_handler(_messages.FileTransferStartUpload, on_start)
    interface.register_handler(_messages.FileTransferPart, on_part)
    return True
