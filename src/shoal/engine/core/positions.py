"""Where a scene kind's controller reads a position from: the :class:`PositionSource` protocol
and :class:`Oracle`, the true positions (the default of every kind). SLO estimates are the other
source (:class:`shoal.engine.slo.positions.Estimated`); a kind on true positions needs nothing
of the localiser, so these two sit below the engine's packages."""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from .snapshot import SnapshotError, part


class PositionSource(Protocol):
    """What a scene kind asks about positions. Shapes: x, y (R, N, 2); owner (R,)."""

    exact: bool  # every robot knows the true positions (the kind may decide once for the swarm)

    def start(self, x: np.ndarray, y: np.ndarray, k: int, seed: int, first_run: int) -> None:
        """A fresh swarm at true positions ``x`` with personal bests ``y`` at tick ``k``."""
        ...

    def observe(self, x: np.ndarray, k: int) -> bool:
        """Localise at the true positions ``x`` once per tick ``k`` (False: done already)."""
        ...

    def keep(self, improved: np.ndarray, offset: np.ndarray | float = 0.0) -> None:
        """Where ``improved`` (R, N), the personal best is now at ``offset`` from the robot."""
        ...

    def to_personal(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Each robot's vector to its own personal best, (R, N, 2)."""
        ...

    def to_owner(self, x: np.ndarray, y: np.ndarray, owner: np.ndarray) -> np.ndarray:
        """Each robot's vector to the personal best of robot ``owner`` (one per run), (R, N, 2)."""
        ...

    def to_centroid(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Each robot's vector to the centroid of all personal bests [7.11], (R, N, 2)."""
        ...

    def placed(self, x: np.ndarray) -> np.ndarray:
        """(R, N, N, 2): where robot i places robot j, itself at its true position."""
        ...

    def resize(self, x: np.ndarray, k: int) -> None:
        """The swarm grew or shrank to the robots at ``x`` at tick ``k``, the first ones kept."""
        ...

    def retune(self, **slo: Any) -> None:
        """New localisation settings (errors, selection, …), beliefs kept."""
        ...

    def snapshot(self) -> dict[str, Any]:
        """What this source keeps from tick to tick, as plain data (:mod:`~shoal.engine.core.snapshot`)."""
        ...

    def restore(self, data: Any, x: np.ndarray) -> None:
        """Continue from :meth:`snapshot`'s ``data`` for the robots at ``x``."""
        ...


class Oracle:
    """Every robot knows every true position."""

    exact = True

    def start(self, x: np.ndarray, y: np.ndarray, k: int, seed: int, first_run: int) -> None:
        pass

    def observe(self, x: np.ndarray, k: int) -> bool:
        return False

    def keep(self, improved: np.ndarray, offset: np.ndarray | float = 0.0) -> None:
        pass

    def to_personal(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return y - x

    def to_owner(self, x: np.ndarray, y: np.ndarray, owner: np.ndarray) -> np.ndarray:
        return y[np.arange(y.shape[0]), owner][:, None, :] - x

    def to_centroid(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return y.mean(axis=1)[:, None, :] - x

    def placed(self, x: np.ndarray) -> np.ndarray:
        return np.broadcast_to(x[:, None, :, :], x.shape[:2] + x.shape[1:])

    def resize(self, x: np.ndarray, k: int) -> None:
        pass

    def retune(self, **slo: Any) -> None:
        raise ValueError("slo: this swarm acts on true positions; switch it to SLO positions first")

    def snapshot(self) -> dict[str, Any]:
        return {"source": "oracle"}

    def restore(self, data: Any, x: np.ndarray) -> None:
        if part(data, "source", "positions") != "oracle":
            raise SnapshotError("positions: the snapshot is of a swarm on SLO positions, this one acts on true ones")
