"""Why Shoal and the thesis differ, per target, written from the target's ``summary.json``.

Each paragraph is a template fed only by the summary (its checks, their verdicts and measured
values, its statistics), so the report's words describe the numbers beside them and cannot go
stale; ``tests/test_report_numbers.py`` holds every number in it to the summary. Causes that a
summary cannot show (what an earlier investigation found) are stated without numbers and point
to docs/readings.md.
"""

from __future__ import annotations

from typing import Any, Callable

from .verdict import FAILS, HOLDS, UNDECIDED

Summary = dict[str, Any]


def check(s: Summary, start: str) -> dict[str, Any] | None:
    """The first check whose name starts with ``start`` (None: the run did not make it)."""
    return next((c for c in s.get("checks", []) if c["name"].startswith(start)), None)


def info(s: Summary, start: str) -> dict[str, Any] | None:
    return next((c for c in s.get("information", []) if c["name"].startswith(start)), None)


def verdict(c: dict[str, Any] | None) -> str:
    return "" if c is None else c.get("verdict") or (HOLDS if c.get("pass") else FAILS)


def counts(s: Summary) -> tuple[int, int, int]:
    vs = [verdict(c) for c in s.get("checks", [])]
    return vs.count(HOLDS), vs.count(FAILS), vs.count(UNDECIDED)


def _measured(c: dict[str, Any] | None) -> str:
    return "" if c is None else str(c["measured"])


def _undecided(s: Summary) -> str:
    held, failed, open_ = counts(s)
    if not open_:
        return ""
    return (f" {'One check is' if open_ == 1 else 'Several checks are'} undecided at {s.get('runs')} runs: the "
            "confidence interval of the statistic straddles the threshold, so more runs would be needed to settle "
            f"{'it' if open_ == 1 else 'them'}.")


def fig3_4(s: Summary) -> str:
    big = str(max(s["swarm_sizes"]))
    b, c = (s["cases"][f"3-4{p}/ahead"][big]["peak_median"] for p in ("b", "c"))
    return (f"Under the `ahead` reading of the attractors (docs/readings.md, \"Attractors in Figure 3-4\") the β = 0.2 "
            f"peaks of the largest swarm are {b:.1f} m/s (case b) and {c:.1f} m/s (case c), above the thesis' 12.4 and "
            "13.4 m/s, and no reading we tried gives those numbers; the checks therefore test the qualitative claims "
            "(never above U, a lower peak for a smaller β, equal β gives equal curves)." + _undecided(s))


def fig3_5(s: Summary) -> str:
    return (f"The thesis gives neither the swarm size nor the seeds of Fig. 3-5; the response times are medians over "
            f"{s['runs']} seeded runs of the largest swarm. Right after U drops, ω·u still carries the old speed, so "
            "the speed bound is checked against the worst-case envelope ω·B + ĉ√d rather than the new U."
            + _undecided(s))


def fig4_6(s: Summary) -> str:
    parts = ["The thesis gives no dimensions for its obstacle course, so ours is a seeded course in its spirit and "
             "absolute CoM values belong to each course. Collision claims are judged as the thesis shows them, at "
             "the end of the median run (Fig. 4-7), over every run that could be the median one; a collision is a "
             "contact deeper than the float-noise allowance of docs/readings.md, and both robots of a robot-robot "
             "contact are disabled."]
    kin, phy = info(s, "[kinematic] adapted-dvc: no robot"), info(s, "[physics] adapted-dvc: no robot")
    if kin and phy:
        parts.append(f"Over every run, as information, Adapted RPSO + DVC is not collision-free: {kin['measured']} "
                     f"with kinematic motion, {phy['measured']} with physics; the median run has none.")
    low = check(s, "[kinematic] adapted-c3-high has the lowest")
    if verdict(low) == FAILS:
        parts.append(f"With kinematic motion Adapted RPSO with large c3 is not the lowest case ({low['measured']}).")
    return " ".join(parts) + _undecided(s)


def fig5_4(s: Summary) -> str:
    guard = check(s, "nonomni-dvc: no robot-robot collision")
    bare = check(s, "nonomni-dvc-noguard: no robot-robot collision")
    every = info(s, "nonomni-dvc: no robot-robot collision in any run")
    speed = check(s, "nonomni-dvc: the robots keep moving")
    parts = ["DVC bounds the newly added velocity but not the carried-over ω·u (docs/readings.md, \"The DVC guard "
             "(ours)\"), so without our guard robots collide"]
    if bare:
        parts[0] += f" (Algorithm 2 as written: {bare['measured']})"
    parts[0] += "."
    if guard and every:
        parts.append(f"With the guard a typical run is collision-free ({guard['measured']}); over every run "
                     f"{every['measured']}.")
    if speed:
        parts.append(f"The robots do not roam as the thesis describes: {speed['measured']} "
                     f"({'below' if verdict(speed) == FAILS else 'against'} our threshold).")
    return " ".join(parts) + _undecided(s)


def fig5_5(s: Summary) -> str:
    end = check(s, "nonomni-dvc (guard on, ours) ends ahead")
    mid = check(s, "nonomni-dvc (guard on, ours) is ahead")
    bare = check(s, "nonomni-dvc-noguard (guard off, Algorithm 2 as written) ends ahead")
    parts = []
    if mid and end:
        parts.append(f"With our guard the non-omnidirectional swarm is ahead of the omnidirectional one at mid-run "
                     f"({mid['measured']}) and at the end ({end['measured']}).")
    if bare:
        parts.append(f"As written (no guard) its robots disable each other and it falls behind ({bare['measured']}).")
    return " ".join(parts) + _undecided(s)


def _generic(s: Summary) -> str:
    held, failed, open_ = counts(s)
    return "" if not failed and not open_ else _undecided(s).strip()


TEMPLATES: dict[str, Callable[[Summary], str]] = {
    "fig3-4": fig3_4, "fig3-5": fig3_5, "fig4-6": fig4_6, "fig5-4": fig5_4, "fig5-5": fig5_5,
}


def why(target: str, summary: Summary) -> str:
    """The "Why" paragraph of ``target`` from its summary ("" when there is nothing to explain)."""
    return TEMPLATES.get(target, _generic)(summary)
