"""Fig. 8-5: escorting a source that moves right at v_n = 0.1 and 0.25 (Rossides §8.2, p. 182;
Fig. 8-5, p. 187).

40 robots start round the source (disc of 50 m, "Unstated settings of Chapter 8") and escort it with GT-PSO and
the ring obstacle r (preset ``escort-moving``). Panels (docs/readings.md, "Panels of Figure 8-5"): a/b r = 25 m,
c/d r = 50 m at PSD_s = 120 dB, e/f r = 50 m with a louder source (130 dB, our value); a, c, e move at
v_n = 0.1 (0.2 m/s), b, d, f at v_n = 0.25 (0.5 m/s) [8.8]. 2000 steps; averages and maps
over the second half, in the frame of the moving source.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

from . import chapter78 as ch
from . import verdict as vd
from .fig8_4 import run_escort
from .output import check
from .verdict import Estimate

PRESET = "escort-moving"
DEFAULT_RUNS = 20
HORIZON = 2000
EXTENT = 300.0
LEVEL = 0.01  # 1 % contour (Fig. 8-5)
LOUD = 130.0  # dB, the unstated louder source ("Panels of Figure 8-5")
CASES = tuple(
    ch.EscortCase(f"{panel}-r{r:g}-{psd:g}dB-vn{vn:g}", 40, r, vn, psd, "source")
    for panel, r, psd, vn in (("a", 25.0, 120.0, 0.1), ("b", 25.0, 120.0, 0.25), ("c", 50.0, 120.0, 0.1),
                              ("d", 50.0, 120.0, 0.25), ("e", 50.0, LOUD, 0.1), ("f", 50.0, LOUD, 0.25))
)
LOST = 3.0  # contact counts as lost when the mean robot–source distance exceeds LOST·r


def run(out_dir: Path, runs: int = DEFAULT_RUNS, workers: int = 1, progress: bool = True, *,
        steps: int = HORIZON, cases: Sequence[ch.EscortCase] = CASES, mode: str = "waveform") -> dict[str, Any]:
    return run_escort(out_dir, "fig8-5", PRESET, cases, runs, workers, progress, steps, EXTENT, LEVEL, mode,
                      _checks, "Fig. 8-5: moving source (+x), occupancy in the source frame over steps {w}–{K} "
                      "(1 % contour white, ring r red)")


def _checks(stats: dict[str, dict[str, Any]], cases: Sequence[ch.EscortCase], est: dict[str, dict[str, Estimate]],
            batches: dict[str, ch.SonarBatch]) -> list[dict[str, Any]]:
    checks = []
    by = {(c.r, c.psd_s, c.v_n): c for c in cases}
    for c in cases:
        st = stats[c.name]
        d, final, com = st["median_mean_dist_to_source"], st["median_final_mean_dist"], st["median_com_dist"]
        e = est[c.name]
        if c.v_n <= 0.1:
            checks.append(check(f"{c.name}: v_n = {c.v_n:g} is tracked (median mean robot–source distance ≤ 1.5 r "
                                "over the window and at the end; threshold ours)", "follows and surrounds the source",
                                f"window {d:.1f} m, end {final:.1f} m (r = {c.r:g} m)",
                                d <= 1.5 * c.r and final <= 1.5 * c.r,
                                vd.all_of(vd.at_most(e["dist"], 1.5 * c.r), vd.at_most(e["final"], 1.5 * c.r))))
            checks.append(check(f"{c.name}: the source stays inside the swarm (median |CoM − source| < r)",
                                "surrounds the source", f"{com:.1f} m (r = {c.r:g} m)", com < c.r,
                                vd.below(e["com"], c.r)))
            continue
        slow = by.get((c.r, c.psd_s, 0.1))
        if slow is not None:
            s0 = stats[slow.name]
            checks.append(check(f"{c.name}: v_n = {c.v_n:g} lags behind the v_n = 0.1 panel (median |CoM − source| "
                                "and mean robot–source distance both larger)", "at v_n = 0.25 the swarm always lags",
                                f"CoM {com:.1f} vs {s0['median_com_dist']:.1f} m; mean distance {d:.1f} vs "
                                f"{s0['median_mean_dist_to_source']:.1f} m",
                                com > s0["median_com_dist"] and d > s0["median_mean_dist_to_source"],
                                vd.all_of(vd.less(est[slow.name]["com"], e["com"]),
                                          vd.less(est[slow.name]["dist"], e["dist"]))))
        if c.r == 50.0 and c.psd_s == 120.0:
            checks.append(check(f"{c.name}: contact is lost (median mean robot–source distance at the end > "
                                f"{LOST:g} r and above its window mean; threshold ours)",
                                "lags badly and loses contact",
                                f"end {final:.1f} m, window {d:.1f} m (r = {c.r:g} m)",
                                final > LOST * c.r and final > d,
                                vd.all_of(vd.above(e["final"], LOST * c.r), vd.less(e["dist"], e["final"]))))
        else:
            checks.append(check(f"{c.name}: lags without runaway (median mean robot–source distance at the end ≤ "
                                f"{LOST:g} r; threshold ours)", "lags and cannot encircle, but no loss of contact",
                                f"end {final:.1f} m (r = {c.r:g} m)", final <= LOST * c.r,
                                vd.at_most(e["final"], LOST * c.r)))
    return checks
