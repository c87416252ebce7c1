"""A scene at one step, kept: :meth:`Scene.snapshot` takes one, ``shoal.make(snapshot=...)`` goes
on from it, with the same bits as the scene it was taken from would have gone on.

A :class:`Snapshot` is the validated scenario, the engine's state as plain data (every array,
counter and generator state a run depends on: :mod:`shoal.engine.core.snapshot`) and the metric
rows recorded so far. :meth:`Snapshot.to_bytes` writes it as one ``.npz`` archive with a JSON
header, never a pickle, so it can travel between processes or sit on disk; reading it imports
nothing it names. Bad or truncated bytes raise :class:`SnapshotError`.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from shoal import __version__
from shoal.engine.core.snapshot import MAX_BYTES, SnapshotError, from_bytes, to_bytes
from shoal.presets.io import PresetError, validate
from shoal.presets.models import Scenario

__all__ = ["Snapshot", "SnapshotError", "snapshot_of"]


@dataclass(frozen=True, eq=False)
class Snapshot:
    """One scene at step :attr:`k`: its :attr:`scenario`, its engine's state (:attr:`engine`, plain
    data), its recorded metric rows (:attr:`rows`: column → (steps, runs) array, or None) and
    trajectory rows (:attr:`trajectories`, or None)."""

    scenario: Scenario
    kind: str
    k: int
    engine: dict[str, Any] = field(repr=False)
    rows: dict[str, np.ndarray] | None = field(default=None, repr=False)
    shoal: str = __version__
    trajectories: np.ndarray | None = field(default=None, repr=False)  # (steps, runs × robots, columns), or None

    def to_bytes(self) -> bytes:
        """The snapshot as an ``.npz`` archive: arrays as ``.npy`` members, the rest (the scenario
        included) as JSON. No pickle."""
        header = {"shoal": self.shoal, "kind": self.kind, "k": self.k,
                  "scenario": self.scenario.model_dump(mode="json")}
        return to_bytes(header, {"engine": self.engine, "rows": self.rows, "trajectories": self.trajectories})

    @classmethod
    def from_bytes(cls, blob: bytes, *, max_bytes: int = MAX_BYTES) -> Snapshot:
        """The snapshot :meth:`to_bytes` wrote; :class:`SnapshotError` for anything else, or for
        one that would unpack to more than ``max_bytes``. Nothing is built: a server can price
        :attr:`scenario` before it makes the scene."""
        header, data = from_bytes(blob, max_bytes)
        raw = header.get("scenario")
        if not isinstance(raw, dict):
            raise SnapshotError("snapshot: its header holds no scenario")
        try:
            scenario = validate(raw)
        except PresetError as e:
            raise SnapshotError(f"snapshot: its scenario is not valid here: {e}") from None
        kind, k = header.get("kind"), header.get("k")
        if not isinstance(kind, str) or not isinstance(k, int) or isinstance(k, bool) or k < 0:
            raise SnapshotError("snapshot: its header names no kind and step")
        if not isinstance(data, dict) or not isinstance(data.get("engine"), dict):
            raise SnapshotError("snapshot: it holds no engine state")
        rows = data.get("rows")
        if rows is not None and not (isinstance(rows, dict) and all(isinstance(v, np.ndarray) for v in rows.values())
                                     and len({v.shape for v in rows.values()}) <= 1):
            raise SnapshotError("snapshot: its metric rows are not columns of one shape")
        paths = data.get("trajectories")
        if paths is not None and not (isinstance(paths, np.ndarray) and paths.ndim == 3 and paths.dtype == float):
            raise SnapshotError("snapshot: its trajectories are not one (steps, rows, columns) array")
        return cls(scenario, kind, k, data["engine"], rows, str(header.get("shoal", "")), paths)

    def save(self, path: str | Path, *, overwrite: bool = False) -> Path:
        """Write :meth:`to_bytes` to ``path`` completely or not at all; an existing file is kept
        unless ``overwrite``."""
        path = Path(path)
        if path.exists() and not overwrite:
            raise FileExistsError(f"{path}: exists already (pass overwrite=True to replace it)")
        write_atomically(path, self.to_bytes())
        return path

    @classmethod
    def load(cls, path: str | Path) -> Snapshot:
        """The snapshot saved at ``path``."""
        return cls.from_bytes(Path(path).read_bytes())


def snapshot_of(value: Snapshot | bytes | str | Path) -> Snapshot:
    """A :class:`Snapshot`, its bytes, or the path of a saved one, as a :class:`Snapshot`."""
    if isinstance(value, Snapshot):
        return value
    if isinstance(value, (bytes, bytearray, memoryview)):
        return Snapshot.from_bytes(bytes(value))
    if isinstance(value, (str, Path)):
        return Snapshot.load(value)
    raise TypeError(f"snapshot: give a Snapshot, its bytes or a file's path, got {type(value).__name__}")


def write_atomically(path: Path, data: bytes) -> None:
    """``data`` into ``path`` through a temporary file in the same folder, renamed into place."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent or Path("."))
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
