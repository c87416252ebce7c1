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
    api = (tmp_path / "site" / "api" / "index.html").read_text(encoding="utf-8")
    assert api.count("shoal.api.scene.make") >= 1
    # what a plug-in author needs: the entries, seeding, presets of a package, the app API and the kit
    for name in ("VelocityLaw", "ObjectiveFunction", "run_generators", "add_presets", "SceneKind", "AppKind",
                 "BaseDriver", "KindPanel", "PlotSpec", "check_kind", "parametrize_with_kinds"):
        assert re.search(rf'id="shoal\.[\w.]*{name}"', api), f"{name} is not in the reference"
    assert (tmp_path / "site" / "reproduction" / "REPRODUCTION" / "index.html").is_file()


VALIDATION = re.search(r"^validation:.*?(?=^\S)", (ROOT / "mkdocs.yml").read_text(encoding="utf-8"), re.M | re.S)


def test_every_docs_page_is_in_the_navigation_and_every_link_is_checked():
    """Strict mode turns the validation's warnings into errors: a page left out of the nav, a link
    to a missing page or a missing anchor fails the build."""
    assert VALIDATION is not None
    for setting in ("omitted_files", "unrecognized_links", "anchors"):
        assert re.search(rf"^  {setting}: warn$", VALIDATION.group(0), re.M), setting


def test_a_dead_anchor_fails_the_build(tmp_path):
    """The site's own link check, on a page with a link to an anchor that does not exist."""
    assert VALIDATION is not None
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "index.md").write_text("# Home\n\n## A heading\n\n[there](#a-heading), [nowhere](#no-such)\n")
    (tmp_path / "mkdocs.yml").write_text("site_name: t\nstrict: true\n" + VALIDATION.group(0))
    done = run([sys.executable, "-m", "mkdocs", "build", "-f", str(tmp_path / "mkdocs.yml"), "--site-dir",
                str(tmp_path / "site")])
    assert done.returncode != 0 and "#no-such" in done.stderr and "#a-heading" not in done.stderr, done.stderr[-2000:]


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
