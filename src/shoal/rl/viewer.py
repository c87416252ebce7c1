"""``render_mode="human"``: a viser page that shows the running environment's arena, frame by frame.

The page is served on this machine only (127.0.0.1, the first free port from 8080; ``address``
says which) and shows the frames :mod:`shoal.rl.render` draws, updated at each step and each
``render()``. Closing the environment stops the server.
"""

from __future__ import annotations

import numpy as np


class Viewer:
    """One viser server with one image on its page."""

    def __init__(self, title: str, host: str = "127.0.0.1", port: int = 8080) -> None:
        import viser

        self.server = viser.ViserServer(host=host, port=port, label=f"Shoal: {title}", verbose=False)
        self.server.gui.add_markdown(f"**{title}**: the environment's arena, as `render()` draws it")
        self._image: object | None = None

    @property
    def address(self) -> str:
        return f"http://127.0.0.1:{self.server.get_port()}"

    def show(self, frame: np.ndarray) -> None:
        if self._image is None:
            self._image = self.server.gui.add_image(frame, label="arena", format="png")
        else:
            self._image.image = frame  # type: ignore[attr-defined]

    def close(self) -> None:
        self.server.stop()
