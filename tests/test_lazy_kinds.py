"""Only the kind you run is imported: the kinds' registry names engines and builders by string,
so ``shoal run`` of a Chapter 3 preset loads no fleet, sonar or SLO module, nor numba, scipy.special
or pymunk (a short run stays on the numpy tick, the compiled tick's numbers), and a scene of any
kind loads no other kind's engine or builder. Each case runs in a fresh interpreter and reads its
``sys.modules``."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from shoal.presets.kinds import KINDS

LATER_CHAPTERS = ("shoal.engine.robots", "shoal.engine.acoustics", "shoal.engine.slo")  # packages, with their modules
HEAVY = ("numba", "scipy.special", "pymunk")
# what only other commands need: a warm-up's child process, a pool of run blocks, writing TOML, "did you
# mean", the values' marks
NOT_FOR_A_RUN = ("subprocess", "concurrent.futures", "tomli_w", "difflib", "shoal.presets.marks")


def modules_after(code: str) -> list[str]:
    """``sys.modules`` of a fresh interpreter (no plug-ins) once ``code`` has run."""
    done = subprocess.run([sys.executable, "-c", code + "\nimport json, sys; print(json.dumps(sorted(sys.modules)))"],
                          capture_output=True, text=True, timeout=300, env={**os.environ, "SHOAL_PLUGINS": "off"})
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.splitlines()[-1])


def under(name: str, packages: tuple[str, ...]) -> bool:
    return any(name == p or name.startswith(p + ".") for p in packages)


def own_modules(kind) -> tuple[str, ...]:
    """The engine module and the builder module a kind's entry names."""
    return tuple(ref.partition(":")[0] for ref in (kind.engine, kind.builder) if isinstance(ref, str))


def test_a_chapter3_run_imports_no_later_chapter_nor_numba(tmp_path):
    loaded = modules_after(f"from shoal.app.cli import main; main(['run', 'default', '--steps', '10', '--out', "
                           f"{str(tmp_path / 'out')!r}])")
    assert (tmp_path / "out" / "metrics.csv").is_file()
    assert "shoal.engine.kinds.swarm" in loaded
    others = [m for k in KINDS.values() if k.name != "swarm" for m in own_modules(k)]
    wrong = [m for m in loaded if under(m, LATER_CHAPTERS) or m in others or under(m, HEAVY + NOT_FOR_A_RUN)]
    assert not wrong, f"a Chapter 3 run imported {wrong}"


@pytest.mark.parametrize("name", [k.name for k in KINDS.values()])
def test_a_scene_of_one_kind_imports_no_other_kinds_engine_or_builder(name):
    kind = KINDS[name]
    loaded = modules_after(f"import shoal\nscene = shoal.make({kind.example!r}, runs=1)\n"
                           "if hasattr(scene.engine, 'compiled'): scene.engine.compiled = False\nscene.step(2)")
    own = own_modules(kind)
    assert set(own) <= set(loaded)
    others = sorted({m for k in KINDS.values() if k.name != name for m in own_modules(k)} - set(own))
    assert not set(others) & set(loaded), f"a {kind.label} imported {sorted(set(others) & set(loaded))}"
