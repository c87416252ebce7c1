"""Every citation can be followed: code, presets, tests and docs cite the theses (equation and
page) and docs/readings.md, never documents outside the repository or their ambiguity IDs, and
every section of docs/readings.md that a file names by its heading exists."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
READINGS = ROOT / "docs" / "readings.md"
TREES = ("benchmarks", "docs", "src", "tests", ".ci")

# Built from pieces so that this file does not match itself.
SECTION = "§"
FORBIDDEN = {
    "a section of the unpublished spec": re.compile(r"\bspec ?" + SECTION, re.IGNORECASE),
    "the unpublished design document": re.compile(r"\bDESIGN" + r"\.md\b"),
    "a file of the unpublished spec": re.compile(r"\bspec/(?:control|acoustics|slo)\b"),
    "a gap/FIX ID of the spec": re.compile(r"\b(?:gap|fix) A[0-9]+", re.IGNORECASE),
    "an ambiguity ID of the spec": re.compile(r"\bA[0-9]{1,2}\b|\bspec [AL][0-9]+\b"),
}
POINTER = re.compile(r"docs/readings\.md,\s+(?:see\s+)?(?:\"([^\"]+)\"|'([^']+)')")


def _tracked() -> list[Path]:
    """The repository's text files: ``git ls-files``, or the source trees without git."""
    try:
        out = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True, timeout=60)
        names = [n for n in out.stdout.decode().split("\0") if n]
    except (OSError, subprocess.SubprocessError):
        names = [str(p.relative_to(ROOT)) for t in TREES for p in (ROOT / t).rglob("*") if p.is_file()]
        names += ["README.md", "pyproject.toml"]
    files = []
    for name in names:
        path = ROOT / name
        if path.is_file() and path.resolve() != Path(__file__).resolve():
            data = path.read_bytes()
            if b"\0" not in data[:8192]:
                files.append(path)
    return files


def _text(path: Path) -> str:
    return path.read_bytes().decode("utf-8", errors="replace")


def _headings() -> set[str]:
    return {m.group(1).strip() for m in re.finditer(r"(?m)^#{2,3} (.+)$", READINGS.read_text(encoding="utf-8"))}


def test_the_scan_sees_the_repository():
    names = {p.relative_to(ROOT).as_posix() for p in _tracked()}
    assert {"README.md", "docs/readings.md", "src/shoal/engine/acoustics/receiver.py",
            "src/shoal/presets/models.py"} <= names


@pytest.mark.parametrize("what", sorted(FORBIDDEN))
def test_no_citation_of_documents_outside_the_repository(what):
    pattern = FORBIDDEN[what]
    hits = [f"{p.relative_to(ROOT)}:{n}: {line.strip()[:100]}"
            for p in _tracked() for n, line in enumerate(_text(p).splitlines(), 1) if pattern.search(line)]
    assert not hits, (f"{len(hits)} line(s) cite {what}; cite the thesis (equation, page) and the heading "
                      "of docs/readings.md instead:\n" + "\n".join(hits[:40]))


def test_every_readings_section_named_in_the_repository_exists():
    headings = _headings()
    missing = []
    for path in _tracked():
        # join wrapped comments and docstrings so that a heading split over lines reads whole
        text = re.sub(r"[ \t]*\n[ \t]*(?:#[ \t]*)?", " ", _text(path))
        for m in POINTER.finditer(text):
            cited = " ".join((m.group(1) or m.group(2)).split())
            if not any(h == cited or h.startswith(cited + " (") for h in headings):
                missing.append(f"{path.relative_to(ROOT)}: {cited!r}")
    assert len(headings) > 50
    assert not missing, "no such heading in docs/readings.md:\n" + "\n".join(missing)


def test_the_contents_list_every_section():
    text = READINGS.read_text(encoding="utf-8")
    contents = text.split("## Contents", 1)[1].split("\n## ", 1)[0]
    listed = {re.sub(r"\\(.)", r"\1", m) for m in re.findall(r"^\s*- \[(.+)\]\(#", contents, re.MULTILINE)}
    assert listed == _headings() - {"Contents"}
