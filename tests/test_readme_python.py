"""The README's "Use it from Python" example runs as written (about ten lines: make, run, metrics,
trajectories, snapshot) and links the tutorial and the plug-ins docs."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_readme_python_example_runs(tmp_path):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Use it from Python", 1)[1].split("\n## ", 1)[0]
    assert "(docs/tutorial.md)" in section and "(docs/plugins.md)" in section
    (code,) = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(code.strip().splitlines()) <= 12
    for call in ("shoal.make(", ".run(", "trajectories()", ".snapshot()", "snapshot="):
        assert call in code, call
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "com_fitness" in done.stdout and (tmp_path / "course-dvc-200.npz").stat().st_size > 1000
