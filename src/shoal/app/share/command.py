"""``shoal export-replay``: a seeded run of a preset as one HTML page, written atomically.

The run may be long (``sim.steps`` up to ten million): its cost (:func:`shoal.studies.cost.cost`)
is said before it starts when it is more than :data:`SAY_SECONDS`, a progress bar follows the
steps, and Ctrl-C (or SIGTERM) stops it at once, writing nothing."""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Iterable

from shoal.studies.cost import cost

SUFFIXES = (".html", ".htm")
MARK = b'id="shoal-run-data"'  # the JSON block every page this command writes carries (share/page.py)
SAY_SECONDS = 10.0  # an export estimated to take longer says so before it starts


class ExportError(ValueError):
    """A bad preset, a bad ``--out`` or a scene the app cannot show, in one line."""


def _is_page(path: Path) -> bool:
    """Is ``path`` a page this command wrote (it may then be replaced)?"""
    try:
        return MARK in path.read_bytes()
    except OSError:
        return False


def check_out(out: Path) -> None:
    """Refuse an ``--out`` that cannot become the page, before anything is run."""
    if out.is_dir():
        raise ExportError(f"--out {out}: is a folder; name the .html file to write")
    if out.suffix.lower() not in SUFFIXES:
        raise ExportError(f"--out {out}: the page needs a name ending in .html")
    if out.exists() and not _is_page(out):
        raise ExportError(f"--out {out}: exists and is not a page shoal export-replay wrote; it is left as it is "
                          "(choose another name)")
    parent = out.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise ExportError(f"--out {out}: {parent} is not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ExportError(f"--out {out}: cannot write in {parent}")


def export_replay(preset: str, out: str | Path, *, seed: int | None = None, steps: int | None = None,
                  sets: Iterable[str] = ()) -> str:
    """Run ``preset`` (``--set`` overrides, seed, steps) and write its page to ``out``; returns
    what was written, in words. Raises :class:`ExportError`; ``out`` is then untouched."""
    from tqdm import tqdm

    from shoal.presets.io import PresetError, load

    from .export import preset_html, write_html

    out = Path(out)
    overrides = list(sets)
    for value, key in ((seed, "sim.seed"), (steps, "sim.steps")):
        if value is not None:
            overrides.append(f"{key}={value}")
    try:
        scenario = load(preset, overrides)
    except PresetError as err:
        raise ExportError("bad preset: " + "; ".join(err.messages)) from None
    check_out(out)
    n = scenario.sim.steps
    estimate = cost(scenario, runs=1)
    if estimate.seconds > SAY_SECONDS:
        print(f"export-replay: {estimate.describe()} at least (drawn as the app draws it, it takes longer: the "
              "progress bar shows the time left); Ctrl-C stops it and writes nothing", file=sys.stderr, flush=True)
    try:
        with tqdm(total=n, desc=f"export {scenario.name}", unit="step", disable=n < 200 or None) as bar:
            page = preset_html(scenario, on_steps=bar.update)
    except PresetError as err:
        raise ExportError(f"{preset}: " + "; ".join(err.messages)) from None
    try:
        write_html(out, page)
    except OSError as err:
        raise ExportError(f"--out {out}: {err.strerror or err}") from None
    return (f"wrote {out} ({out.stat().st_size / 2**20:.1f} MiB: {scenario.name}, seed {scenario.sim.seed}, "
            f"steps 0–{n}; open it in any browser)")
