"""The code style and the layering, enforced: ``ruff check`` and ``lint-imports`` (contracts
in pyproject.toml) run here as CI runs the suite, so a stray import or a lint slip fails it."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = ROOT / "pyproject.toml"


def _run(args: list[str], cwd: Path, **env: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], cwd=cwd, capture_output=True, text=True, timeout=300,
                          env={**os.environ, **env})


def test_ruff_is_clean():
    res = _run(["-m", "ruff", "check", "--no-cache", "."], ROOT)
    assert res.returncode == 0, res.stdout + res.stderr


def test_import_contracts_hold():
    """``lint-imports`` run plainly from the checkout: the package is ``src/shoal``, so the
    checkout's own code is read, never an installed copy."""
    lint = "import sys; from importlinter.cli import lint_imports_command; sys.exit(lint_imports_command())"
    res = _run(["-c", lint, "--config", str(PYPROJECT), "--no-cache"], ROOT, PYTHONPATH=str(ROOT / "src"))
    assert "Contracts:" in res.stdout and res.returncode == 0, res.stdout + res.stderr
