"""The "Why" paragraphs of the reproduction report say what their summary's checks say: a
settled check as it fell, an undecided one as its point estimate with "not settled" beside
its numbers, and trends read from the numbers, not assumed."""

from __future__ import annotations

from shoal.studies.experiments import TARGETS
from shoal.studies.experiments.output import check
from shoal.studies.experiments.verdict import Verdict, exact


def _check(name: str, measured: str, passed: bool, outcome: str, runs: int = 20) -> dict:
    return check(name, "", measured, passed, Verdict(outcome, runs))


def _fig7_5(*checks: dict) -> dict:
    return {"target": "fig7-5", "runs": 20, "checks": list(checks)}


RATIO = "A-PSO: time ∝ 1/U at Q = 1.5 (median time at U = 2 over U = 12; pass: within ×1.5 of 6; threshold ours)"
X_FASTER = "X-PSO faster than A-PSO wherever both converge (Q = 1.5, median times)"


def test_a_missed_inverse_u_says_which_way_from_its_numbers():
    fast = TARGETS["fig7-5"].why(_fig7_5(_check(RATIO, "4752 / 194 = 24.56", False, "fails")))
    assert "A-PSO's time falls faster than 1/U: 4752 / 194 = 24.56, where 1/U gives 6." in fast
    slow = TARGETS["fig7-5"].why(_fig7_5(_check(RATIO, "400 / 200 = 2", False, "fails")))
    assert "falls more slowly than 1/U: 400 / 200 = 2, where 1/U gives 6." in slow
    held = TARGETS["fig7-5"].why(_fig7_5(_check(RATIO, "1200 / 200 = 6", True, "holds")))
    assert "1/U" not in held


def test_an_undecided_check_is_said_as_its_point_estimate_and_not_settled():
    numbers = "U 2: X 4286 vs A 4752; U 8: X 396 vs A 355"
    text = TARGETS["fig7-5"].why(_fig7_5(_check(X_FASTER, numbers, False, "undecided")))
    assert f"X-PSO is not faster than A-PSO at every U ({numbers}; not settled at 20 runs)" in text
    text = TARGETS["fig7-5"].why(_fig7_5(_check(X_FASTER, numbers, False, "fails")))
    assert f"X-PSO is not faster than A-PSO at every U ({numbers})," in text and "not settled" not in text
    assert "X-PSO is" not in TARGETS["fig7-5"].why(_fig7_5(_check(X_FASTER, numbers, True, "holds")))


def _slo_neighbourhood(measured: str, outcome: str = "undecided", early: list[dict] | None = None) -> dict:
    rts = _check("random, RTS: hardly affected by p after generation 25 (largest / smallest <= 1.5; threshold ours)",
                 measured, outcome == "holds", outcome, 31)
    return {"target": "slo-neighbourhood", "runs": 31, "checks": [*(early or []), rts]}


def test_the_trend_of_rts_in_p_is_read_from_its_numbers():
    why = TARGETS["slo-neighbourhood"].why
    assert "its error falls as p rises (p=0.3: 21.5, p=0.5: 16.3, p=0.9: 11.6; not settled at 31 runs)" in why(
        _slo_neighbourhood("p=0.3: 21.5, p=0.5: 16.3, p=0.9: 11.6"))
    assert "its error grows as p rises (p=0.3: 1.5, p=0.5: 6.3, p=0.9: 11.6)." in why(
        _slo_neighbourhood("p=0.3: 1.5, p=0.5: 6.3, p=0.9: 11.6", "fails"))
    assert "its error changes with p" in why(_slo_neighbourhood("p=0.3: 21.5, p=0.5: 6.3, p=0.9: 11.6"))


def test_the_readings_that_show_the_early_lead_are_named_whole():
    def early(reading: str, passed: bool) -> dict:
        return check(f"random, CSS: in generations 1-5 p = 0.3 and 0.5 do better than p = 0.9 ({reading})", "",
                     "p=0.3: 1, p=0.5: 2, p=0.9: 3", passed, exact(passed))

    text = TARGETS["slo-neighbourhood"].why(_slo_neighbourhood("p=0.3: 2, p=0.5: 2, p=0.9: 2", "holds", [
        early("frozen, the default", False), early("non-neighbours carried by dead reckoning (an extension)", True)]))
    assert "shows under: non-neighbours carried by dead reckoning (an extension) (holds)." in text
