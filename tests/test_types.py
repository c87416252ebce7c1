"""The whole package type-checks: mypy (pinned in the test extras, configured in pyproject.toml
with ``files = ["src/shoal"]``) is clean on every module of src/shoal, so the annotations a user's
type checker reads (the package ships ``py.typed``) are ones mypy has checked."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "shoal"


def test_mypy_is_clean_on_the_whole_package():
    done = subprocess.run([sys.executable, "-m", "mypy", "--no-incremental"], capture_output=True, text=True,
                          cwd=ROOT, timeout=900)
    assert done.returncode == 0, done.stdout[-5000:]
    checked = re.search(r"in (\d+) source files", done.stdout)
    modules = sum(1 for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)
    assert checked is not None and int(checked.group(1)) == modules, done.stdout[-500:]  # no module left out


def test_the_package_is_marked_typed():
    assert (PACKAGE / "py.typed").is_file()
