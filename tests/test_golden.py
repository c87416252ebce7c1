"""Golden outputs: a short seeded ``shoal run`` of every shipped preset, hashed.

A change that should not alter numbers keeps every hash here byte-identical. A change that
alters them on purpose regenerates them in its own commit and says why:

    SHOAL_UPDATE_GOLDEN=1 python -m pytest tests/test_golden.py

The runs are short (2 runs × 40 steps) so that floating-point noise cannot grow into a
different decision; every scene kind is covered: the Chapter 3 swarm, the Chapter 4–5 fleet
(kinematic and pymunk), the Chapter 6–8 acoustic swarm, Mai's SLO swarm and the three host
swarms on SLO positions.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import pytest

from shoal.app.cli import main
from shoal.presets.io import list_presets

GOLDEN = Path(__file__).parent / "golden" / "run_hashes.json"
FILES = ("run.json", "trajectories.csv", "metrics.csv")
ARGS = ("--runs", "2", "--seed", "7", "--steps", "40")


def _digest(path: Path) -> str:
    data = path.read_bytes()
    if path.name == "run.json":  # the package version is not a number of the run
        meta = json.loads(data)
        meta.pop("shoal_version", None)
        data = json.dumps(meta, sort_keys=True).encode()
    return hashlib.sha256(data).hexdigest()[:16]


def _run(preset: str, out: Path) -> dict[str, str]:
    assert main(["run", preset, *ARGS, "--out", str(out)]) == 0
    return {name: _digest(out / name) for name in FILES}


def _stored() -> dict[str, dict[str, str]]:
    return json.loads(GOLDEN.read_text()) if GOLDEN.exists() else {}


@pytest.mark.parametrize("preset", list(list_presets()))
def test_golden_run(preset, tmp_path, capsys):
    got = _run(preset, tmp_path / preset)
    capsys.readouterr()
    if os.environ.get("SHOAL_UPDATE_GOLDEN"):
        stored = _stored()
        stored[preset] = got
        GOLDEN.parent.mkdir(exist_ok=True)
        GOLDEN.write_text(json.dumps(dict(sorted(stored.items())), indent=1) + "\n")
        return
    want = _stored().get(preset)
    assert want is not None, f"no golden hashes for {preset}: run with SHOAL_UPDATE_GOLDEN=1"
    assert got == want, (f"{preset}: `shoal run {preset} {' '.join(ARGS)}` no longer gives the stored outputs; "
                         "if the change is meant, regenerate in its own commit (see this module's docstring)")


def test_every_preset_has_golden_hashes():
    assert sorted(_stored()) == sorted(list(list_presets()))
