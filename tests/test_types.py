"""The registries and the code that reads them type-check: mypy (pinned in the test extras,
configured in pyproject.toml) is clean on these parts of src/shoal. Not yet listed: the thesis
reproductions (studies/experiments: 30 errors, mostly optional arrays of the batch records) and
the app (about 100, most in the panel and the kinds' modules)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CHECKED = ("src/shoal/engine", "src/shoal/presets", "src/shoal/api", "src/shoal/studies/sweep",
           "src/shoal/studies/cost.py")


def test_mypy_is_clean():
    done = subprocess.run([sys.executable, "-m", "mypy", "--no-incremental", *CHECKED], capture_output=True, text=True,
                          cwd=ROOT, timeout=900)
    assert done.returncode == 0, done.stdout[-5000:]
