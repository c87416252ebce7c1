"""The tutorial runs as written on the README's plain install: a fresh virtual environment made by
the README's own command (``python3 -m venv .venv && . .venv/bin/activate && pip install .``) runs
every code block of ``docs/tutorial.md``, pandas included (it is a dependency, not a test extra).

Slow (about two minutes: a whole install from the package index); it runs in CI with the rest."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def readme_install() -> list[str]:
    """The README's quick-start command, cut at its ``pip install`` (what a reader types to install)."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"## Install and start the app.*?```bash\n(.*?)```", text, re.S)
    assert block, "the README's install section has no command"
    steps = [s.strip() for s in block.group(1).strip().split("&&")]
    venv = next(s for s in steps if s.startswith("python3 -m venv"))
    pip = next(s for s in steps if s.startswith("pip install"))
    assert venv == "python3 -m venv .venv" and pip == "pip install .", (venv, pip)
    return pip.split()[1:]


@pytest.mark.slow
def test_the_tutorial_runs_on_the_readmes_plain_install(tmp_path):
    args = readme_install()
    tree = tmp_path / "shoal"  # a copy of the checkout: the build writes nothing into it
    shutil.copytree(ROOT / "src", tree / "src", ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, tree / name)
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH", "SHOAL_PLUGINS")}
    try:
        subprocess.run([sys.executable, "-m", "venv", str(tree / ".venv")], check=True, timeout=300)
        python = tree / ".venv" / "bin" / "python"
        done = subprocess.run([str(python), "-m", "pip", *args], cwd=tree, capture_output=True, text=True,
                              timeout=900, env=env)
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-3000:]
        tutorial = (ROOT / "docs" / "tutorial.md").read_text(encoding="utf-8")
        blocks = re.findall(r"```python\n(.*?)```", tutorial, re.S)
        assert len(blocks) >= 6
        work = tmp_path / "work"
        work.mkdir()
        done = subprocess.run([str(python), "-c", "\n".join(blocks)], cwd=work, capture_output=True, text=True,
                              timeout=900, env=env, input="")
        assert done.returncode == 0, done.stderr[-3000:]
        assert "['beta']" in done.stdout and "Name: com_fitness" in done.stdout  # a pandas groupby printed
        assert list(work.iterdir()) == []  # the tutorial leaves nothing where it runs
    finally:
        shutil.rmtree(tree, ignore_errors=True)
