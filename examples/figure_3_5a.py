"""Reproduce the curve of Rossides' Fig. 3-5a with the API: 1000 one-dimensional particles under
Adapted PSO tuned by the top speed U and acceleration A+ (U steps 20 → 4 → 20 m/s at 34 s and
67 s, A+ = 4 m/s², Δt = 1 s). The highest speed in the swarm stays within U [3.26]: it falls
under the new U in one tick when U drops, and climbs by at most A+·Δt a tick [3.35] when U rises.

    python examples/figure_3_5a.py [OUT.png]
"""

from __future__ import annotations

import sys

import numpy as np

import shoal


def u_of(t: np.ndarray) -> np.ndarray:
    """The preset's schedule of U [m/s]."""
    return np.where(t < 34.0, 20.0, np.where(t < 67.0, 4.0, 20.0))


def main(out: str | None = None) -> int:
    scene = shoal.make("fig3-5a")
    table = scene.run()  # the preset's 100 steps, one metric row per step
    t, speed = np.asarray(table["t"]), np.asarray(table["max_speed"])
    assert np.all(speed[1:] <= u_of(t[1:] - 1.0) + 1e-9), "the speed stays within the U of its tick"
    assert np.all(np.diff(speed) <= 4.0 + 1e-9), "it climbs by at most A+·Δt a tick"
    print(f"max speed at 30 s {speed[30]:.2f} m/s (U = 20), at 60 s {speed[60]:.2f} m/s (U = 4), "
          f"at 99 s {speed[99]:.2f} m/s (U = 20)")
    if out:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 3.2))
        ax.plot(t, speed, label="max |u| (Shoal)")
        ax.step(t, u_of(t), where="post", ls="--", label="U")
        ax.set(xlabel="t [s]", ylabel="speed [m/s]", title="Fig. 3-5a: steps of U with A+ = 4 m/s²")
        ax.legend()
        fig.tight_layout()
        fig.savefig(out, dpi=120)
        print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else None))
