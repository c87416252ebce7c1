"""The camera every tab starts with: straight down on the ground plane, far and narrow (close
to an orthographic top view). Views scale their world so that the arena fills ``VIEW_HALF``
scene units around the middle of the screen, so the camera need not move between scenes."""

from __future__ import annotations

import math

VIEW_HALF = 10.0  # the arena's half size in scene units
CAMERA_FOV = math.radians(8.0)
CAMERA_HEIGHT = 1.12 * VIEW_HALF / math.tan(CAMERA_FOV / 2)


def camera_height(aspect: float) -> float:
    """Camera height that shows the whole arena (plus a margin) in a canvas of ``aspect`` = width/height."""
    aspect = aspect if math.isfinite(aspect) and aspect > 0 else 1.0
    return CAMERA_HEIGHT * max(1.0, 1.0 / aspect)
