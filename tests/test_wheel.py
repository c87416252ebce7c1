"""The wheel holds the whole package: every module and data file under ``src/shoal`` (packages
are found, not listed, so a new sub-package cannot be left out of an install while the editable
checkout still works)."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "shoal"
SHIPPED = {".py", ".toml", ".md", ".typed"}  # code, presets and lesson files, teaching notes, the py.typed marker


def _source_files() -> set[str]:
    files = set()
    for path in PACKAGE.rglob("*"):
        if path.is_file() and path.suffix in SHIPPED and "__pycache__" not in path.parts:
            files.add(path.relative_to(ROOT / "src").as_posix())
    return files


def test_the_wheel_holds_every_module_and_data_file(tmp_path):
    tree = tmp_path / "tree"  # a copy, so the build writes nothing into the checkout
    tree.mkdir()
    shutil.copytree(PACKAGE, tree / "src" / "shoal", ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(ROOT / name, tree / name)
    res = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                          "-w", str(tmp_path / "dist"), str(tree)], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stdout + res.stderr
    (wheel,) = (tmp_path / "dist").glob("shoal-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    want = _source_files()
    assert len(want) > 200 and {"shoal/studies/sweep/run.py", "shoal/py.typed"} <= want
    missing = sorted(want - names)
    assert not missing, f"{len(missing)} file(s) of src/shoal are not in the wheel: {missing[:20]}"
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names), "the wheel ships no LICENSE"
