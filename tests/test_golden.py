"""Golden outputs: a short seeded ``shoal run`` of every shipped preset, hashed.

A change that should not alter numbers keeps every hash here byte-identical. A change that
alters them on purpose regenerates them in its own commit and says why:

    SHOAL_UPDATE_GOLDEN=1 python -m pytest tests/test_golden.py

The runs are short (2 runs × 40 steps) so that floating-point noise cannot grow into a
different decision; every scene kind is covered: the Chapter 3 swarm, the Chapter 4–5 fleet
(kinematic and pymunk), the Chapter 6–8 acoustic swarm, Mai's SLO swarm and the three host
swarms on SLO positions.

The hashes are the same on every x86-64 CPU with AVX2 and FMA (x86-64-v3, most made since
2013) or AVX-512: :func:`test_golden_on_other_cpus` runs every preset again with numpy's
AVX-512 loops switched off and other OpenBLAS kernels (engine/core/portable.py says which
steps needed care). The versions
that wrote the hashes are kept beside them (``golden/environment.json``); a failure names what
differs from them.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

import pytest
from pydantic import BaseModel, ConfigDict, create_model

from shoal.app.cli import main
from shoal.presets.io import list_presets, load
from shoal.presets.kinds import KINDS, SceneKind
from shoal.presets.models import Scenario

GOLDEN = Path(__file__).parent / "golden" / "run_hashes.json"
ENVIRONMENT = GOLDEN.with_name("environment.json")
PACKAGES = ("numpy", "scipy", "numba", "llvmlite", "pymunk", "pydantic")
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


def _cpu_dispatch() -> list[str]:
    """numpy's optional SIMD targets this CPU runs (its dispatched loops), [] if it cannot say."""
    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    except ImportError:  # numpy < 2
        try:
            from numpy.core._multiarray_umath import __cpu_dispatch__, __cpu_features__
        except ImportError:
            return []
    return [f for f in __cpu_dispatch__ if __cpu_features__.get(f)]


def environment() -> dict[str, str]:
    """What could move a last bit: Python, the numeric packages, the machine and numpy's SIMD."""
    env = {"python": platform.python_version(), "machine": platform.machine(), "system": platform.system(),
           "numpy_simd": " ".join(_cpu_dispatch())}
    env.update({name: importlib.metadata.version(name) for name in PACKAGES})
    return env


def _env_note() -> str:
    """The versions that wrote the hashes beside this run's, differences first."""
    then = json.loads(ENVIRONMENT.read_text()) if ENVIRONMENT.exists() else {}
    now = environment()
    differ = [f"{k} {then.get(k, '?')} -> {now.get(k, '?')}" for k in now if then.get(k) != now.get(k)]
    return ("the hashes were written with the same versions and machine as this run" if not differ else
            "this run differs from the one that wrote the hashes in: " + "; ".join(differ))


@pytest.mark.parametrize("preset", list(list_presets()))
def test_golden_run(preset, tmp_path, capsys):
    got = _run(preset, tmp_path / preset)
    capsys.readouterr()
    if os.environ.get("SHOAL_UPDATE_GOLDEN"):
        stored = _stored()
        stored[preset] = got
        GOLDEN.parent.mkdir(exist_ok=True)
        GOLDEN.write_text(json.dumps(dict(sorted(stored.items())), indent=1) + "\n")
        ENVIRONMENT.write_text(json.dumps(environment(), indent=1) + "\n")
        return
    want = _stored().get(preset)
    assert want is not None, f"no golden hashes for {preset}: run with SHOAL_UPDATE_GOLDEN=1"
    differ = [name for name in FILES if got.get(name) != want.get(name)]
    assert not differ, (f"{preset}: `shoal run {preset} {' '.join(ARGS)}` no longer gives the stored "
                        f"{', '.join(differ)} (kept in {tmp_path / preset}); {_env_note()}. If the change is meant, "
                        "regenerate in its own commit (see this module's docstring)")


def test_every_preset_has_golden_hashes():
    assert sorted(_stored()) == sorted(list(list_presets()))


# (OpenBLAS kernel, numpy SIMD targets switched off): an AVX2 machine (Intel before AVX-512, AMD Zen 1-3), and
# OpenBLAS's plainest kernel. A CPU without AVX2 and FMA (x86-64-v2) rounds numpy's complex products otherwise
# (no fused multiply-add): the two escorting XB-PSO presets then differ; so do other architectures (arm64).
OTHER_CPUS = {"avx2": ("Haswell", lambda f: "AVX512" in f or f == "X86_V4"),
              "plain-blas": ("Prescott", lambda f: False)}
HASH_ALL = """
import contextlib, io, json, sys, tempfile
from pathlib import Path
sys.path.insert(0, sys.argv[1])
from test_golden import ARGS, FILES, _digest
from shoal.app.cli import main
from shoal.presets.io import list_presets
out = {}
with tempfile.TemporaryDirectory() as tmp:
    for preset in list_presets():
        with contextlib.redirect_stdout(io.StringIO()):
            assert main(["run", preset, *ARGS, "--out", f"{tmp}/{preset}"]) == 0
        out[preset] = {name: _digest(Path(tmp, preset, name)) for name in FILES}
print(json.dumps(out))
"""


@pytest.mark.parametrize("cpu", list(OTHER_CPUS))
def test_golden_on_other_cpus(cpu):
    """The stored hashes come out again with OpenBLAS's kernel and numpy's SIMD loops of
    another CPU."""
    kernel, beyond = OTHER_CPUS[cpu]
    disable = [f for f in _cpu_dispatch() if beyond(f)]
    env = {**os.environ, "OPENBLAS_CORETYPE": kernel, "NPY_DISABLE_CPU_FEATURES": " ".join(disable)}
    done = subprocess.run([sys.executable, "-c", HASH_ALL, str(Path(__file__).parent)], env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    got = json.loads(done.stdout.strip().splitlines()[-1])
    moved = sorted(p for p, h in got.items() if h != _stored().get(p))
    assert not moved, (f"as on an {cpu} CPU (OpenBLAS {kernel}, numpy without {' '.join(disable) or 'nothing'}) "
                       f"these presets give other outputs: {', '.join(moved)}; a step of theirs depends on the "
                       "CPU (see engine/core/portable.py)")


class ThrowawaySection(BaseModel):
    """The section of a kind that exists only in the test below."""

    model_config = ConfigDict(extra="forbid")
    speed: float = 1.0


@pytest.mark.parametrize("preset", ["default", "course-dvc"])
def test_a_new_kind_changes_no_golden(preset, tmp_path, capsys):
    """A scene kind added (here registered, with a section of its own) leaves every other kind's
    outputs byte for byte as they were: run.json leaves unset sections out, so it does not grow a
    ``"throwaway": null``."""
    kind = SceneKind("throwaway", "throwaway kind", "shoal.engine.kinds.swarm:Simulation",
                     "shoal.presets.builders.swarm:build_simulation", "throwaway", model=ThrowawaySection)
    KINDS.register(kind)
    try:
        got = _run(preset, tmp_path / preset)
    finally:
        KINDS.unregister("throwaway")
    capsys.readouterr()
    assert got == _stored()[preset]
    assert "throwaway" not in json.loads((tmp_path / preset / "run.json").read_text())["preset"]


def test_a_new_built_in_section_is_left_out_while_unset():
    """A kind built in as a new optional ``Scenario`` field: a scenario without it dumps as before."""
    wider = create_model("WiderScenario", __base__=Scenario, throwaway=(ThrowawaySection | None, None))
    for preset in ("default", "course-dvc", "sonar-xb-pso", "slo-walk"):
        sc = load(preset)
        assert wider.model_validate(sc.model_dump()).model_dump(mode="json") == sc.model_dump(mode="json")
    unset = [n for n, f in Scenario.model_fields.items() if f.default is None]
    assert unset and not set(unset) & set(load("default").model_dump())  # world, acoustics, slo: left out
