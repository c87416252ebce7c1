"""Shoal runs where its install cannot be written and its user's home either: the compiled
kernels are cached in the user's cache folder, or compiled in memory, never an error.

Each case runs ``shoal run`` in a fresh process on a copy of the package that cannot be
written: read-only, and (so that root, who writes anywhere, is held too) with a file where
each ``__pycache__`` folder would go."""

from __future__ import annotations

import hashlib
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest

import shoal

RUN = ["run", "default", "--steps", "3", "--seed", "4"]
SCRIPT = ("import sys; sys.path.insert(0, sys.argv[1]); import shoal; assert shoal.__file__.startswith(sys.argv[1]); "
          "from shoal.app.cli import main; from shoal.engine.core import compiled; code = main(sys.argv[2:]); "
          "import numpy as np; from shoal.engine.core.portable import ordered_matmul; "
          "ordered_matmul(np.ones((2, 3)), np.ones((3, 2)));"  # one kernel compiled for sure (the run may end on numpy)
          "print('uncached:', len(compiled.uncached)); sys.exit(code)")


@pytest.fixture(scope="module")
def read_only_install(tmp_path_factory) -> Path:
    """A copy of the package that nobody, root included, can cache into."""
    site = tmp_path_factory.mktemp("site")
    shutil.copytree(Path(shoal.__file__).parent, site / "shoal", ignore=shutil.ignore_patterns("__pycache__"))
    for folder in [site / "shoal", *(p for p in (site / "shoal").rglob("*") if p.is_dir())]:
        (folder / "__pycache__").write_text("not a folder")
    for path in [site, *site.rglob("*")]:
        path.chmod(path.stat().st_mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))
    yield site
    for path in [site, *site.rglob("*")]:
        path.chmod(path.stat().st_mode | stat.S_IWUSR)


def _env(home: Path, **extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME")}
    env.update(HOME=str(home), PYTHONDONTWRITEBYTECODE="1", **extra)
    return env


def _shoal(site: Path, out: Path, env: dict[str, str]) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", SCRIPT, str(site), *RUN, "--out", str(out)], env=env,
                          capture_output=True, text=True, timeout=600)


def _digest(out: Path) -> str:
    return hashlib.sha256((out / "trajectories.csv").read_bytes() + (out / "metrics.csv").read_bytes()).hexdigest()


def _files(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


def test_a_read_only_install_caches_in_the_users_cache_folder(read_only_install, tmp_path):
    before = _files(read_only_install)
    home = tmp_path / "home"
    home.mkdir()
    done = _shoal(read_only_install, tmp_path / "r", _env(home))
    assert done.returncode == 0, done.stderr[-3000:]
    assert "uncached: 0" in done.stdout
    cached = list((home / ".cache" / "shoal" / "numba").rglob("*.nbi"))
    assert cached, "no kernel index in ~/.cache/shoal/numba"
    assert _files(read_only_install) == before  # nothing written into the install


def test_a_read_only_install_with_an_unwritable_home_runs_uncached(read_only_install, tmp_path):
    home = tmp_path / "home"
    home.mkdir()
    (home / ".cache").write_text("not a folder")  # ~/.cache cannot be made, for root too
    done = _shoal(read_only_install, tmp_path / "r", _env(home))
    assert done.returncode == 0, done.stderr[-3000:]
    assert "cannot cache" not in done.stderr and "Traceback" not in done.stderr
    assert "uncached: 0" not in done.stdout  # compiled in memory
    writable = tmp_path / "home2"
    writable.mkdir()
    again = _shoal(read_only_install, tmp_path / "r2", _env(writable))
    assert again.returncode == 0 and _digest(tmp_path / "r") == _digest(tmp_path / "r2")  # the same numbers


def test_numba_cache_dir_chooses_the_folder(read_only_install, tmp_path):
    home = tmp_path / "home"
    home.mkdir()
    chosen = tmp_path / "kernels"
    done = _shoal(read_only_install, tmp_path / "r", _env(home, NUMBA_CACHE_DIR=str(chosen)))
    assert done.returncode == 0, done.stderr[-3000:]
    assert list(chosen.rglob("*.nbi")) and not (home / ".cache").exists()
