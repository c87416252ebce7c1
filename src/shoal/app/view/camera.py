"""The camera every tab starts with: straight down on the ground plane, far and narrow (close
to an orthographic top view). Views scale their world so that the arena fills ``VIEW_HALF``
scene units around the middle of the screen, so the camera need not move between scenes."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

VIEW_HALF = 10.0  # the arena's half size in scene units
CAMERA_FOV = math.radians(8.0)
CAMERA_HEIGHT = 1.12 * VIEW_HALF / math.tan(CAMERA_FOV / 2)
WIDE = 1.25  # the home view shows at least ±WIDE·VIEW_HALF across: the colour bar and its labels beside the arena
WIDE_PER_SCALE = 0.15  # … and this much more per unit of text scale above 1 (the labels of projector mode)


def camera_height(aspect: float, text_scale: float = 1.0) -> float:
    """Camera height that shows the whole arena (plus a margin, and across it the colour bar
    beside it, with its labels at ``text_scale``) in a canvas of ``aspect`` = width/height."""
    aspect = aspect if math.isfinite(aspect) and aspect > 0 else 1.0
    wide = WIDE + WIDE_PER_SCALE * max(0.0, text_scale - 1.0)
    return CAMERA_HEIGHT * max(1.0, wide / 1.12 / aspect)


def top_view(server: Any) -> None:
    """Set up a viser server (``ViserServer``) for a flat arena seen from above: the initial camera
    straight down, +z up, and the default lights without shadows. Nothing in a flat arena casts a
    shadow, but viser's lights cast them by default: three cascaded shadow maps drawn every frame
    and sampled by every pixel of the ground grid, most of a frame in a software-rendered page."""
    cam = server.initial_camera
    cam.position, cam.look_at, cam.up = (0.0, 0.0, CAMERA_HEIGHT), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0)
    cam.fov, cam.near, cam.far = CAMERA_FOV, 1.0, 4.0 * CAMERA_HEIGHT
    server.scene.set_up_direction("+z")
    server.scene.configure_default_lights(enabled=True, cast_shadow=False)


def home_camera(camera: Any, text_scale: float = 1.0) -> None:
    """Put a client's camera (viser ``CameraHandle``) back straight above the middle of the
    screen at the height that shows the arena (undoes a user's orbit, pan and zoom), its labels at
    ``text_scale``. A camera whose report is not finite or of an empty canvas (the message guard
    drops such reports) gets the height of a square one."""
    try:
        aspect = float(camera.aspect)
    except (ArithmeticError, TypeError, ValueError):
        aspect = 1.0
    camera.position = (0.0, 0.0, camera_height(aspect, text_scale))
    camera.look_at = (0.0, 0.0, 0.0)
    camera.up_direction = (0.0, 1.0, 0.0)


TIP_TOLERANCE = math.radians(1.0)  # a top view looks this close to straight down


def tipped(camera: Any) -> bool:
    """Does a client's camera (viser ``CameraHandle``) look anywhere but straight down, by more than
    :data:`TIP_TOLERANCE`? (A camera with no report yet, or at its target, is not tipped.)"""
    try:
        position, look_at = (tuple(float(v) for v in p) for p in (camera.position, camera.look_at))
    except Exception:  # no report yet
        return False
    d = [b - a for a, b in zip(position, look_at)]
    n = math.hypot(*d)
    if not math.isfinite(n) or n == 0:
        return False
    return -d[2] / n < math.cos(TIP_TOLERANCE)


def straighten(camera: Any) -> None:
    """Put a tipped camera straight above the point it looks at, at the same distance, +y up: a
    user's pan and zoom stay, the tilt goes."""
    look_at = tuple(float(v) for v in camera.look_at)
    distance = math.dist(tuple(float(v) for v in camera.position), look_at)
    camera.position = (look_at[0], look_at[1], look_at[2] + distance)
    camera.up_direction = (0.0, 1.0, 0.0)


@dataclass(frozen=True)
class Viewport:
    """What a browser's camera shows of the scene: the scene point in the middle of the screen,
    half the height shown (scene units) and width / height. The default is the home camera of a
    square canvas (a page with no camera reports, such as a shared run)."""

    centre: tuple[float, float] = (0.0, 0.0)
    half_height: float = CAMERA_HEIGHT * math.tan(CAMERA_FOV / 2)
    aspect: float = 1.0

    @classmethod
    def of(cls, camera: Any) -> "Viewport":
        """The viewport of a viser ``CameraHandle`` looking down (its distance to what it looks at)."""
        position, look_at = (tuple(float(v) for v in p) for p in (camera.position, camera.look_at))
        distance = math.dist(position, look_at)
        aspect = float(camera.aspect)
        ok = all(map(math.isfinite, (distance, aspect, float(camera.fov)))) and distance > 0 and aspect > 0
        if not ok:
            return cls()
        return cls((look_at[0], look_at[1]), distance * math.tan(float(camera.fov) / 2), aspect)
