"""The code style and the layering, enforced: ``ruff check`` and ``lint-imports`` (contracts
in pyproject.toml) run here as CI runs the suite, so a stray import or a lint slip fails it."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = ROOT / "pyproject.toml"


def _run(args: list[str], cwd: Path, **env: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], cwd=cwd, capture_output=True, text=True, timeout=300,
                          env={**os.environ, **env})


def test_ruff_is_clean():
    res = _run(["-m", "ruff", "check", "--no-cache", "."], ROOT)
    assert res.returncode == 0, res.stdout + res.stderr


def package_tree(where: Path) -> Path:
    """The ``shoal`` package as the installer lays it out (pyproject's package-dir map), made of
    links into the checkout: import-linter reads one package folder, and here ``shoal.engine``
    lives in ``engine/``, not ``shoal/engine/``."""
    dirs = tomllib.loads(PYPROJECT.read_text())["tool"]["setuptools"]["package-dir"]
    top = where / "shoal"
    top.mkdir()
    for f in (ROOT / dirs["shoal"]).glob("*.py"):
        (top / f.name).symlink_to(f)
    for name, folder in dirs.items():
        if name != "shoal":
            (top / name.removeprefix("shoal.")).symlink_to(ROOT / folder, target_is_directory=True)
    return where


def test_import_contracts_hold(tmp_path):
    tree = package_tree(tmp_path)
    lint = "import sys; from importlinter.cli import lint_imports_command; sys.exit(lint_imports_command())"
    res = _run(["-c", lint, str(PYPROJECT), "--no-cache"], tree, PYTHONPATH=str(tree))
    assert "Contracts:" in res.stdout and res.returncode == 0, res.stdout + res.stderr
