"""Shoal's public Python API (also importable from ``shoal`` itself).

* :func:`make` a :class:`Scene` from a preset name, a file, a dict or a scenario, with keyword
  overrides; step it, read ``scene.state`` and ``scene.row()``, ``retune`` it live, collect
  ``scene.metrics()`` as a table; keep it with ``scene.snapshot()`` (a :class:`Snapshot`, bytes
  without pickle) and go on from it with ``make(snapshot=...)``;
* :func:`run` one preset and :func:`sweep` a grid of preset fields in memory (the numbers
  ``shoal run`` and ``shoal sweep`` write);
* :func:`register` your own objective, law, robot law, strategy, selection or scene kind, or
  install a package that does so (entry points of ``shoal.plugins``).
"""

from .batch import run, sweep
from .register import plugins, register, register_objective, registry_for
from .scene import Scene, make, scenario_of
from .snapshot import Snapshot, SnapshotError
from .tables import as_table

__all__ = ["Scene", "Snapshot", "SnapshotError", "as_table", "make", "plugins", "register", "register_objective",
           "registry_for", "run", "scenario_of", "sweep"]
