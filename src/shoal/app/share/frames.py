"""Which recorded steps an exported page keeps: every ``stride``-th step counted from the first
(by step number, as the trails thin theirs) and always the last, at most :func:`frame_budget`
frames: :data:`MAX_FRAMES`, fewer for a large swarm, so that a page stays a few MB."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

MAX_FRAMES = 600  # frames in one exported page, whatever the run's length
MAX_ROBOT_FRAMES = 120_000  # robots × frames in one page (about 15 bytes each once compressed)
MIN_FRAMES = 50  # a large swarm still gets this many
MAX_FPS = 30.0  # frames a second a page plays at 1× at most (what a browser draws smoothly)


def seconds_per_frame(steps_per_second: float) -> float:
    """The page's clock between two frames: the app's pace, at most :data:`MAX_FPS` frames a second."""
    return 1.0 / min(float(steps_per_second), MAX_FPS)


def frame_budget(robots: int, max_frames: int = MAX_FRAMES) -> int:
    """The most frames a page of ``robots`` robots keeps."""
    return max(min(max_frames, MIN_FRAMES), min(max_frames, MAX_ROBOT_FRAMES // max(robots, 1)))


@dataclass(frozen=True)
class FramePlan:
    """The steps kept out of ``first``…``last`` (every ``stride``-th, plus ``last``)."""

    first: int
    last: int
    stride: int
    steps: tuple[int, ...]

    @property
    def frames(self) -> int:
        return len(self.steps)


def stride_for(span: int, max_frames: int = MAX_FRAMES) -> int:
    """The smallest stride that keeps at most ``max_frames`` of ``span + 1`` consecutive steps."""
    if max_frames < 2:
        raise ValueError(f"max_frames must be >= 2 (got {max_frames})")
    if span + 1 <= max_frames:
        return 1
    return math.ceil(span / (max_frames - 1))  # at most max_frames - 1 strides, plus a shorter last one


def plan(steps: np.ndarray | list[int], max_frames: int = MAX_FRAMES) -> FramePlan:
    """The frames to keep of recorded step numbers ``steps`` (increasing)."""
    ks = np.asarray(steps, dtype=np.int64)
    if ks.size == 0:
        raise ValueError("no recorded steps")
    first, last = int(ks[0]), int(ks[-1])
    stride = stride_for(last - first, max_frames)
    keep = ks[(ks - first) % stride == 0]
    if keep[-1] != last:
        keep = np.append(keep, last)
    while len(keep) > max_frames:  # gaps in the recorded steps: thin further
        stride += 1
        keep = ks[(ks - first) % stride == 0]
        keep = keep if keep[-1] == last else np.append(keep, last)
    return FramePlan(first=first, last=last, stride=stride, steps=tuple(int(k) for k in keep))


def run_plan(steps: int, max_frames: int = MAX_FRAMES) -> FramePlan:
    """The frames to keep of a seeded run of ``steps`` steps (step 0, the start, included)."""
    stride = stride_for(steps, max_frames)
    kept = list(range(0, steps + 1, stride))
    if kept[-1] != steps:
        kept.append(steps)
    return FramePlan(first=0, last=steps, stride=stride, steps=tuple(kept))
