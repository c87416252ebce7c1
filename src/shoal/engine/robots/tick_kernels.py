"""The whole kinematic fleet tick in one compiled call: phase A (costs and bests), the draws,
the attractors on true positions, phase B (:func:`.kernels.phase_b`'s per-run part) and the
metrics of :meth:`~shoal.engine.kinds.fleet.Fleet.info`, run by run.

A tick of a small fleet in numpy around :func:`.kernels.phase_b` is a few dozen calls on tiny
arrays, more than the kernel's own work below a few hundred robots. :func:`fleet_runs` repeats
that numpy in its order (the cost's ``norm``, the honest bests of ``pso/bests.py``, the
mean's pairwise sum, the maximum's NaN) and draws each run's U(0,1) numbers from its own
generator as ``Generator.random`` would, so its bits are the numpy tick's
(``tests/test_fleet_tick.py``). Each run reads and writes its own rows only, so blocks of
runs may go to parallel threads (:mod:`shoal.engine.core.parallel`).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.compiled import kernel
from ..core.compiled_draws import double_at
from ..core.sums import pairwise_stack, pairwise_sum_in
from .kernels import ACTIVE, Grid, Outputs, TickParams, WorldArrays, _maximum, _phase_b_run, _scratch

STATE = ("x", "heading", "u", "cmd", "status", "slow", "y", "f_y")  # what a tick reads and writes anew


@kernel
def _admissible(v: float) -> bool:
    """A cost that may be a best (``pso.bests.admissible``, minimising): not NaN, not +inf."""
    return v == v and v != np.inf


@kernel
def _best_of(a: np.ndarray) -> int:
    """``pso.bests.best_of`` of a row (minimising): the first least admissible value, else 0."""
    best = -1
    for i in range(a.shape[0]):
        if _admissible(a[i]) and (best < 0 or a[i] < a[best]):
            best = i
    return max(best, 0)


@kernel
def fleet_runs(lo: int, hi: int, old: tuple, new: tuple, f: np.ndarray, yg: np.ndarray, best: np.ndarray,
               source: np.ndarray, fn: int, states: np.ndarray, terms: int, per_component: bool, params: tuple,
               world: tuple, grid: tuple, outputs: tuple, layer_x: np.ndarray, stall_speed: float, stall_steps: int,
               com: np.ndarray, max_speed: np.ndarray, counts: np.ndarray) -> bool:
    """One tick of runs ``lo … hi − 1``: the state at step k in ``old`` and anew in ``new``
    (the arrays of :data:`STATE`, (R, N, …) each; ``new`` also the commands before collisions
    zeroed them, ``FleetState.commanded``), the costs ``f``, bests ``yg`` and ``best``,
    and the outputs (filled for these runs). ``fn`` and ``states`` are the runs' generators
    (:attr:`~shoal.engine.core.compiled_draws.CompiledDraws.address`, ``.states``). ``params``,
    ``world``, ``grid`` and ``outputs`` are a :class:`TickParams`, :class:`WorldArrays`,
    :class:`Grid` and :class:`Outputs` as plain tuples (numba types a plain tuple in C, a named
    one through Python: microseconds a call). Metrics per run: ``com`` [4.17],
    ``max_speed``, ``counts`` (4, R): collided, stalled, operational, layers passed. Whether a
    robot sensed."""
    p, w, g, out = TickParams(*params), WorldArrays(*world), Grid(*grid), Outputs(*outputs)
    x0, heading0, u0, cmd0, status0, slow0, y0, f_y0 = old
    x, heading, u, cmd, status, slow, y, f_y, commanded = new
    N = x.shape[1]
    scratch = _scratch(N, g, w)
    draws = np.empty((terms, N, 2 if per_component else 1))
    g_p, g_g, row = np.empty((N, 2)), np.empty((N, 2)), np.empty(N)
    stack = pairwise_stack()
    sensed = False
    for r in range(lo, hi):
        for i in range(N):
            x[r, i, 0], x[r, i, 1] = x0[r, i, 0], x0[r, i, 1]
            u[r, i, 0], u[r, i, 1] = u0[r, i, 0], u0[r, i, 1]
            cmd[r, i, 0], cmd[r, i, 1] = cmd0[r, i, 0], cmd0[r, i, 1]
            heading[r, i], status[r, i] = heading0[r, i], status0[r, i]
            # phase A: the cost at the true position, the bests of the robots still active (never NaN)
            dx, dy = x[r, i, 0] - source[0], x[r, i, 1] - source[1]
            fi = math.sqrt(dx * dx + dy * dy)
            f[r, i] = fi
            if status[r, i] == ACTIVE and _admissible(fi) and (fi < f_y0[r, i] or not _admissible(f_y0[r, i])):
                f_y[r, i], y[r, i, 0], y[r, i, 1] = fi, x[r, i, 0], x[r, i, 1]
            else:
                f_y[r, i], y[r, i, 0], y[r, i, 1] = f_y0[r, i], y0[r, i, 0], y0[r, i, 1]
        b = _best_of(f_y[r])
        yg[r, 0], yg[r, 1], best[r] = y[r, b, 0], y[r, b, 1], f_y[r, b]
        state = states[r]
        for t in range(draws.shape[0]):  # the run's draws of this tick, in Generator.random's order
            for i in range(N):
                for q in range(draws.shape[2]):
                    draws[t, i, q] = double_at(fn, state)
        for i in range(N):  # the attractors on true positions
            g_p[i, 0], g_p[i, 1] = y[r, i, 0] - x[r, i, 0], y[r, i, 1] - x[r, i, 1]
            g_g[i, 0], g_g[i, 1] = yg[r, 0] - x[r, i, 0], yg[r, 1] - x[r, i, 1]
            out.omega[r, i] = np.nan
            for n in range(out.c.shape[0]):
                out.c[n, r, i] = 0.0
            out.force[r, i, 0] = out.force[r, i, 1] = 0.0
            for q in range(out.gap.shape[2]):
                out.gap[r, i, q] = p.sensing_range
                out.point[r, i, q, 0] = out.point[r, i, q, 1] = np.nan
                out.centre[r, i, q, 0] = out.centre[r, i, q, 1] = np.nan
                out.hit[r, i, q] = False
        sensed |= _phase_b_run(r, x, heading, u, cmd, status, g_p, g_g, draws, p, w, g, out, scratch)
        top = -np.inf
        collided = stalled = 0
        for i in range(N):
            commanded[r, i, 0], commanded[r, i, 1] = cmd[r, i, 0], cmd[r, i, 1]  # before a collision zeroes it
            if status[r, i] != ACTIVE:
                cmd[r, i, 0] = cmd[r, i, 1] = 0.0
                u[r, i, 0] = u[r, i, 1] = 0.0
                collided += 1
            speed = math.sqrt(u[r, i, 0] * u[r, i, 0] + u[r, i, 1] * u[r, i, 1])
            slow[r, i] = slow0[r, i] + 1 if status[r, i] == ACTIVE and speed < stall_speed else 0
            stalled += slow[r, i] >= stall_steps
            top = _maximum(top, speed)
            row[i] = x[r, i, 0]
        com[r] = (0.0 + pairwise_sum_in(row, 0, N, stack)) / N  # [4.17], numpy's mean
        max_speed[r] = top
        passed = 0
        for layer in layer_x:
            passed += layer < com[r]
        counts[0, r], counts[1, r], counts[2, r], counts[3, r] = collided, stalled, N - collided, passed
    return sensed
