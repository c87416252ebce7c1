"""Shoal: PSO control of robot swarms, as a Python library, a CLI and a browser app.

The library's calls are here (loaded on first use, so ``import shoal`` stays light)::

    import shoal
    scene = shoal.make("course-dvc", runs=4, seed=7, controller={"alpha": 0.8})
    table = scene.run(200)                               # metrics.csv's rows, as a table
    results = shoal.sweep("course-dvc", {"controller.alpha": [0.5, 0.9]}, runs=8)

See :mod:`shoal.api`. Sub-packages, lowest layer first: ``shoal.engine`` (the simulation),
``shoal.presets`` (scenario models, shipped presets and the registry of scene kinds),
``shoal.studies`` (thesis reproductions and sweeps), ``shoal.api`` (this library's calls) and
``shoal.app`` (the browser app and the ``shoal`` command); ``shoal.static`` holds the teaching
notes and lessons.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.2.0"  # the one place it is written: pyproject.toml, CITATION.cff and every output read it

API = ("Scene", "Snapshot", "SnapshotError", "as_table", "make", "plugins", "register", "register_objective",
       "registry_for", "run", "scenario_of", "sweep")
__all__ = ["__version__", *API]


def __getattr__(name: str) -> Any:
    if name in API:  # (loaded on first use: the command and the app import the root for its version only)
        return getattr(importlib.import_module("shoal.api"), name)
    raise AttributeError(f"module 'shoal' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *API])
