"""The reproduction report's words come from its numbers: every number in a target's README
(and in its section of REPRODUCTION.md) is a number of that target's summary.json, and the
committed READMEs are what the templates render from the committed summaries."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest

from shoal.studies.experiments import TARGETS
from shoal.studies.experiments.report import REPORT

DOCS = Path(__file__).parents[1] / "docs" / "reproduction"
NUMBER = re.compile(r"(?<![\w.\-/#^])[−-]?\d+(?:\.\d+)?(?:e[−+-]?\d+)?(?![\w.]\d)(?!\w)", re.I)
# citations and names whose digits are not measurements: Fig. 4-6, Table 7.1, §4.5.3, [3.11],
# p. 95, Algorithm 2, Chapter 7, SPSO 2011, Tab. 4.3 ...
CITATION = re.compile(
    r"(?:Figs?\.|Figures?|Tables?|Tab\.|§|Sections?|Sec\.|Ch\.|Chs\.|Chapters?|pp?\.|Alg\.|Algorithms?|Eq\.|"
    r"SPSO|Theorem|Appendix)\s*\d+(?:[.\-–]\d+)*[a-f]?(?:(?:\s*(?:,|and|–|-|to)\s*|[/–-])\d+(?:[.\-–]\d+)*[a-f]?)*"
    r"|\[\d+(?:\.\d+)?\](?:–\[\d+(?:\.\d+)?\])?")


def numbers(text: str) -> list[str]:
    """The numbers of a text, without citations, code spans, links, file names and figure
    names (those are names, not measurements)."""
    text = re.sub(r"`[^`]*`", " ", text)
    text = re.sub(r"!?\[[^\]]*\]\([^)]*\)", " ", text)
    text = re.sub(r"[\w\-]+\.(?:png|csv|json|npz|md|toml)\b", " ", text)
    text = re.sub(r"\bfig\d+-\d+\w*\b|\bslo-\w+\b|\b[a-f]-r\d+\S*|\bn\d+-r\d+\b", " ", text)
    text = CITATION.sub(" ", text)
    return [m.group(0).replace("−", "-") for m in NUMBER.finditer(text)]


def _pool(summary: dict) -> list[float]:
    pool: list[float] = []

    def walk(o: object) -> None:
        if isinstance(o, bool) or o is None:
            return
        if isinstance(o, (int, float)):
            pool.append(float(o))
        elif isinstance(o, dict):
            for k, v in o.items():
                walk(k)
                walk(v)
        elif isinstance(o, (list, tuple)):
            for v in o:
                walk(v)
        elif isinstance(o, str):
            pool.extend(float(x) for x in numbers(o))

    walk(summary)
    return [p for p in pool if math.isfinite(p)]


def in_summary(token: str, pool: list[float]) -> bool:
    """``token`` is a number of the summary as written, or rounded to the digits it shows (an
    integer only from a non-integral number, a percentage from a fraction)."""
    v = float(token)
    if "e" in token.lower():
        return any(p != 0 and abs(p - v) <= 0.05 * abs(v) for p in pool)
    decimals = len(token.split(".")[1]) if "." in token else 0
    tol = 0.5 * 10 ** -decimals + 1e-9
    for p in pool:
        if p == v or (p * 100 == v and decimals == 0):
            return True
        if decimals and abs(p - v) <= tol:
            return True
        if not decimals and p != int(p) and abs(p - v) <= tol:
            return True
        if not decimals and abs(100 * p - v) <= 0.5 and p != int(p):
            return True
    return False


def stray_numbers(readme: str, summary: dict) -> list[str]:
    pool = _pool(summary)
    return sorted({t for t in numbers(readme) if not in_summary(t, pool)})


def test_the_number_filter_finds_measurements_and_skips_citations():
    text = "Fig. 4-6 (Table 7.1, §4.5.3, [3.11]): 12 robots took 45.4 m in `fig4-6` and 1.2e-3 s."
    assert numbers(text) == ["12", "45.4", "1.2e-3"]
    pool = _pool({"a": 45.37, "b": "median 12 runs", "c": 0.0012})
    assert stray_numbers(text, {"a": 45.37, "b": "median 12 runs", "c": 0.0012}) == []
    assert stray_numbers("30 runs, 45.5 m", {"a": 45.37}) == ["30", "45.5"]
    assert in_summary("95", [0.95]) and in_summary("3", [3.4]) and in_summary("3.4", [3.4])
    # an integer is not read from another integer, nor from a number that rounds elsewhere
    assert not in_summary("3", [3.6, 2.0]) and not in_summary("3", [30.0]) and not in_summary("3.5", [3.4])
    assert pool


SUMMARIES = sorted(DOCS.glob("*/summary.json"))


@pytest.mark.parametrize("path", SUMMARIES, ids=lambda p: p.parent.name)
def test_every_number_in_a_targets_readme_is_in_its_summary(path):
    summary = json.loads(path.read_text(encoding="utf-8"))
    readme = (path.parent / "README.md").read_text(encoding="utf-8")
    assert not stray_numbers(readme, summary), path.parent.name
    why = TARGETS[summary["target"]].why(summary)
    assert not stray_numbers(why, summary), f"{path.parent.name}: Why"


def section(report: str, target: str) -> str:
    """The part of REPRODUCTION.md about ``target`` (from its anchor to the next one)."""
    parts = re.split(r'<a id="([\w-]+)"></a>', report)
    found = [parts[i + 1] for i in range(1, len(parts) - 1, 2) if parts[i] == target]
    assert len(found) == 1, f"{target}: {len(found)} sections in the report"
    return found[0]


@pytest.mark.parametrize("path", SUMMARIES, ids=lambda p: p.parent.name)
def test_every_number_in_a_targets_report_section_is_in_its_summary(path):
    summary = json.loads(path.read_text(encoding="utf-8"))
    text = section((DOCS / REPORT).read_text(encoding="utf-8"), summary["target"])
    assert not stray_numbers(text, summary), path.parent.name


def test_a_stray_number_in_a_section_is_found():
    report = '<a id="fig3-5"></a>\n\n## fig3-5\n\n12 of 13 checks\n<a id="fig3-4"></a>\n\n31 runs'
    assert stray_numbers(section(report, "fig3-5"), {"checks": [], "verdicts": {"holds": 12}}) == ["13"]
    assert stray_numbers(section(report, "fig3-4"), {"runs": 31}) == []


@pytest.mark.parametrize("path", SUMMARIES, ids=lambda p: p.parent.name)
def test_the_committed_readmes_are_rendered_from_their_summaries(path):
    summary = json.loads(path.read_text(encoding="utf-8"))
    assert (path.parent / "README.md").read_text(encoding="utf-8") == TARGETS[summary["target"]].readme(summary)


def test_the_committed_report_shows_every_targets_why_and_verdict_counts():
    report = (DOCS / REPORT).read_text(encoding="utf-8")
    for path in SUMMARIES:
        summary = json.loads(path.read_text(encoding="utf-8"))
        why = TARGETS[summary["target"]].why(summary)
        if why:
            assert why in report, summary["target"]
        counts = [sum(c["verdict"] == v for c in summary["checks"]) for v in ("holds", "fails", "undecided")]
        assert f"| {len(summary['checks'])} | {counts[0]} | {counts[1]} | {counts[2]} |" in report
