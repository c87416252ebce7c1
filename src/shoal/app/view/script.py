"""The one way Shoal runs its own JavaScript in a tab's page: viser's ``RunJavascriptMessage``
(as the keyboard shortcuts do), sent through a client's GUI or scene API."""

from __future__ import annotations

from typing import Any

from viser import _messages


def run_script(api: Any, source: str) -> None:
    """Run ``source`` in the page of ``api`` (a client's ``GuiApi`` or ``SceneApi``)."""
    api._websock_interface.queue_message(_messages.RunJavascriptMessage(source=source))
