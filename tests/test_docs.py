"""The docs: the site builds with warnings as errors, the data dictionary is the one the kinds'
schemas give, the tutorial's code runs as written and so do the example scripts."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

from shoal.api.dictionary import data_dictionary

ROOT = Path(__file__).resolve().parents[1]
DOCS, EXAMPLES = ROOT / "docs", ROOT / "examples"


def run(args: list[str], **kw) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in __import__("os").environ.items() if k != "SHOAL_PLUGINS"}
    return subprocess.run(args, capture_output=True, text=True, timeout=600, cwd=ROOT, env=env, **kw)


def test_the_site_builds_with_warnings_as_errors(tmp_path):
    done = run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")])
    assert done.returncode == 0, done.stderr[-3000:]
    assert (tmp_path / "site" / "api" / "index.html").read_text(encoding="utf-8").count("shoal.api.scene.make") >= 1


def test_the_data_dictionary_is_current():
    assert (DOCS / "data-dictionary.md").read_text(encoding="utf-8") == data_dictionary(), (
        "regenerate: SHOAL_PLUGINS=off python -m shoal.api.dictionary > docs/data-dictionary.md")


def test_the_tutorial_runs_as_written(tmp_path):
    blocks = re.findall(r"```python\n(.*?)```", (DOCS / "tutorial.md").read_text(encoding="utf-8"), re.S)
    assert len(blocks) >= 5
    done = run([sys.executable, "-c", "\n".join(blocks)], input="")
    assert done.returncode == 0, done.stderr[-3000:]
    assert "['beta']" in done.stdout and "needs a new engine" in done.stdout


def test_the_training_page_runs_as_written():
    """docs/train.md: a random agent, the baseline, a search over ω and c, a frame: no RL library."""
    blocks = re.findall(r"```python\n(.*?)```", (DOCS / "train.md").read_text(encoding="utf-8"), re.S)
    assert len(blocks) >= 5
    done = run([sys.executable, "-c", "\n".join(blocks)], input="")
    assert done.returncode == 0, done.stderr[-3000:]
    out = done.stdout
    assert "random agent: return" in out and "the law: return" in out and "(560, 720, 3) uint8" in out
    law, found = re.search(r"the law's tuning: (-?\d+); searched: .*: (-?\d+)", out).groups()
    assert int(found) > int(law), "the search improved on the law's tuning"


def test_the_example_scripts_run(tmp_path):
    figure = tmp_path / "fig3-5a.png"
    for script, args in (("figure_3_5a.py", [str(figure)]), ("rastrigin_10d.py", []), ("custom_law_app.py", [])):
        done = run([sys.executable, str(EXAMPLES / script), *args])
        assert done.returncode == 0, (script, done.stderr[-3000:])
    assert figure.stat().st_size > 10_000
