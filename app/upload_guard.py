"""Stop an oversized upload while it arrives, not after viser has buffered all of it.

Viser collects every part of an uploaded file in memory and only then calls the upload
button's callback, where the app checks the size (``MAX_UPLOAD_BYTES`` for presets,
``MAX_REPLAY_BYTES`` for replays). A page cannot send more than the file it picked, but
anything that speaks the websocket protocol can declare or send gigabytes. This guard drops
a transfer as soon as its declared or received size passes a limit, frees the parts already
received, and tells the tab why.

It reads viser's bookkeeping of transfers in progress (``GuiApi._current_file_upload_states``,
viser 1.x). If a viser version keeps them elsewhere, :func:`guard_uploads` installs nothing
and says so; the size checks after the upload still hold.
"""

from __future__ import annotations

from typing import Any, Callable

from viser import _messages

Refuse = Callable[[str, int], None]  # (file name, bytes declared or received so far)


def guard_uploads(gui: Any, limit: int, refuse: Refuse) -> bool:
    """On ``gui`` (a client's ``GuiApi``), drop any upload larger than ``limit`` bytes and call
    ``refuse``. Returns whether the guard could be installed."""
    states = getattr(gui, "_current_file_upload_states", None)
    interface = getattr(gui, "_websock_interface", None)
    if not isinstance(states, dict) or interface is None:
        return False

    def drop(transfer_uuid: str, size: int) -> None:
        state = states.pop(transfer_uuid, None)  # later parts of it are then ignored by viser
        if state is not None:
            refuse(str(state.get("filename", "")), size)

    def on_start(client_id: Any, message: _messages.FileTransferStartUpload) -> None:
        if message.size_bytes > limit:
            drop(message.transfer_uuid, message.size_bytes)

    def on_part(client_id: Any, message: _messages.FileTransferPart) -> None:
        state = states.get(message.transfer_uuid)
        if state is not None and state.get("transferred_bytes", 0) > limit:
            drop(message.transfer_uuid, int(state["transferred_bytes"]))

    # Registered after viser's own handlers, so these run once viser has recorded the message.
    interface.register_handler(_messages.FileTransferStartUpload, on_start)
    interface.register_handler(_messages.FileTransferPart, on_part)
    return True
