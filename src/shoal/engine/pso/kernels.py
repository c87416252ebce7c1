"""The compiled Chapter 3 step for small swarms (numba): objective, bests [3.2]/[3.3], velocity
(standard PSO [2.1] or Adapted PSO with sgn [3.11]), position ([2.2] or [3.10]) and
acceleration [3.22] of every run in one call.

A step of a swarm of 10–30 robots in numpy is some thirty calls on tiny arrays, nearly all
overhead. :func:`swarm_step` repeats the numpy step's arithmetic in its order, including how
``np.sum`` adds a row (:func:`numpy_sum`), so its bits are the numpy step's;
``tests/test_pso_kernels.py`` runs both side by side. The objectives without transcendental
functions that differ between numpy and the C library (all but Ackley, whose ``exp`` does)
are evaluated here too; Ackley's values come from numpy.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.compiled import kernel
from ..core.compiled_draws import double_at
from ..core.sums import BLOCK, block_sum

# objectives evaluated in the kernel, by their Objective names; a code is the index
OBJECTIVES = ("source-distance", "linear", "sphere", "rastrigin", "rosenbrock", "griewank")
SOURCE_DISTANCE, LINEAR, SPHERE, RASTRIGIN, ROSENBROCK, GRIEWANK = range(6)
GIVEN = -1  # the caller passes f (numpy)
TWO_PI = 2 * np.pi


MAX_TERMS = BLOCK


@kernel
def numpy_sum(a: np.ndarray, n: int) -> float:
    """``np.sum`` of the first ``n`` ≤ :data:`MAX_TERMS` entries of a contiguous 1-D array, to the
    bit: +0 plus numpy's pairwise sum, which up to 128 terms is one block of 8 accumulators
    (longer rows are halved first; the compiled step leaves dimensions beyond 128 to numpy)."""
    return 0.0 + block_sum(a, 0, n)


@kernel
def objective(code: int, x: np.ndarray, r: int, source: np.ndarray, scale: float, buf: np.ndarray,
              f: np.ndarray) -> None:
    """``f[r, i]``: objective ``code`` at every position ``x[r, i]`` of run r, as
    :class:`~shoal.engine.core.objectives.Objective` computes it (``buf``: scratch of length d)."""
    n, d = x.shape[1], x.shape[2]
    shift = False
    for k in range(d):
        shift = shift or source[k] != 0.0
    for i in range(n):
        if code == LINEAR:
            f[r, i] = x[r, i, 0]
            continue
        if code == SOURCE_DISTANCE:
            for k in range(d):
                t = x[r, i, k] - source[k]
                buf[k] = t * t
            f[r, i] = math.sqrt(0.0 + block_sum(buf, 0, d))
            continue
        for k in range(d):  # the benchmarks see (x − source)/scale (skipping − 0 and / 1 changes no bit they use)
            z = x[r, i, k] - source[k] if shift else x[r, i, k]
            buf[k] = z / scale if scale != 1.0 else z
        if code == SPHERE:
            for k in range(d):
                buf[k] = buf[k] * buf[k]
            f[r, i] = 0.0 + block_sum(buf, 0, d)
        elif code == RASTRIGIN:
            for k in range(d):
                z = buf[k]
                buf[k] = z * z - 10.0 * math.cos(TWO_PI * z)
            f[r, i] = 10.0 * d + (0.0 + block_sum(buf, 0, d))
        elif code == ROSENBROCK:
            if d < 2:
                t = 1.0 - buf[0]
                f[r, i] = t * t
                continue
            for k in range(d - 1):
                q, p = buf[k + 1] - buf[k] * buf[k], 1.0 - buf[k]
                buf[k] = 100.0 * (q * q) + p * p
            f[r, i] = 0.0 + block_sum(buf, 0, d - 1)
        else:  # GRIEWANK
            prod = 1.0
            for k in range(d):
                prod *= math.cos(buf[k] / math.sqrt(k + 1.0))
            for k in range(d):
                buf[k] = buf[k] * buf[k]
            f[r, i] = 1.0 + (0.0 + block_sum(buf, 0, d)) / 4000.0 - prod


@kernel
def _sgn(v: float) -> float:
    if v > 0.0:
        return 1.0
    if v < 0.0:
        return -1.0
    return v


@kernel
def _maximum(a: float, b: float) -> float:
    """numpy's maximum: NaN wins."""
    return a if (a >= b or a != a) else b


@kernel
def _better(a: float, b: float, maximise: bool) -> bool:
    return a > b if maximise else a < b


@kernel
def _admissible(v: float, maximise: bool) -> bool:
    """Not NaN, nor the worst infinity (``bests.admissible``)."""
    return v == v and v != (-np.inf if maximise else np.inf)


@kernel
def _bests(r: int, x: np.ndarray, f: np.ndarray, y: np.ndarray, f_y: np.ndarray, yg: np.ndarray, best: np.ndarray,
           maximise: bool) -> None:
    """[3.2] keep each robot's best, [3.3] the run's best of them (the first on ties), honestly as
    ``bests.improves`` and ``bests.best_of``: NaN and the worst infinity are never bests."""
    n, d = x.shape[1], x.shape[2]
    for i in range(n):
        v = f[r, i]
        if _admissible(v, maximise) and (_better(v, f_y[r, i], maximise) or not _admissible(f_y[r, i], maximise)):
            f_y[r, i] = v
            for k in range(d):
                y[r, i, k] = x[r, i, k]
    g = -1
    for i in range(n):
        v = f_y[r, i]
        if _admissible(v, maximise) and (g < 0 or _better(v, f_y[r, g], maximise)):
            g = i
    if g < 0:
        g = 0
    for k in range(d):
        yg[r, k] = y[r, g, k]
    best[r] = f_y[r, g]


NONE2, NONE3 = np.empty((0, 0)), np.empty((0, 0, 0))  # "the same for every robot"


@kernel
def swarm_step(x: np.ndarray, u: np.ndarray, y: np.ndarray, f_y: np.ndarray, f: np.ndarray, draws: np.ndarray,
               tick: int, omega: float, omega_robots: np.ndarray, c: np.ndarray, c_robots: np.ndarray,
               ahead: np.ndarray, literal: bool, adapted: bool, dt: float, before: bool, maximise: bool, code: int,
               source: np.ndarray, scale: float, new: np.ndarray, yg: np.ndarray, best: np.ndarray, turn: np.ndarray,
               turned: np.ndarray, speeds: np.ndarray) -> None:
    """One tick of every run (:meth:`Simulation.step`) into ``new`` (3, R, N, d): positions,
    velocities, accelerations. ``y``, ``f_y``, ``yg``, ``best`` are updated in place (pass
    copies); ``f`` is filled with the objective at ``x`` unless ``code`` is :data:`GIVEN`;
    ``speeds`` (2, R) gets each run's top speed and top velocity component.

    ``draws[:, tick]`` are the tick's U(0,1) draws, (R, 2, N, d). A robot that moves leaves its
    velocity's first two components (one in 1-D) in ``turn`` (R, N, ≤ 2) and True in ``turned``
    (R, N): its heading, worked out when read (:class:`~shoal.engine.kinds.swarm.Turns`).
    ω, c_1 and c_2 are ``omega`` and ``c`` (2,) for every robot, or ``omega_robots`` (R, N) and
    ``c_robots`` (2, R, N) where those are not empty; ``ahead`` (d,) is both attractors'
    direction unless ``literal``."""
    buf = np.empty(x.shape[2])
    for r in range(x.shape[0]):
        run_tick(r, x, u, y, f_y, f, draws[r, tick], omega, omega_robots, c, c_robots, ahead, literal, adapted, dt,
                 before, maximise, code, source, scale, new, yg, best, turn, turned, speeds, buf)


@kernel
def run_tick(r: int, x: np.ndarray, u: np.ndarray, y: np.ndarray, f_y: np.ndarray, f: np.ndarray, draws: np.ndarray,
             omega: float, omega_robots: np.ndarray, c: np.ndarray, c_robots: np.ndarray, ahead: np.ndarray,
             literal: bool, adapted: bool, dt: float, before: bool, maximise: bool, code: int, source: np.ndarray,
             scale: float, new: np.ndarray, yg: np.ndarray, best: np.ndarray, turn: np.ndarray, turned: np.ndarray,
             speeds: np.ndarray, buf: np.ndarray) -> None:
    """Run r's part of :func:`swarm_step`, its draws ``draws`` (2, N, d); ``buf``: scratch of length d.
    It reads and writes row r of every array only."""
    N, d = x.shape[1], x.shape[2]
    per_robot = omega_robots.shape[0] > 0
    if code != GIVEN:
        objective(code, x, r, source, scale, buf, f)
    if before:  # Algorithm 1 phase A first
        _bests(r, x, f, y, f_y, yg, best, maximise)
    top = big = -np.inf
    for i in range(N):
        w, c1, c2 = (omega_robots[r, i], c_robots[0, r, i], c_robots[1, r, i]) if per_robot else (omega, c[0], c[1])
        move = False
        for k in range(d):
            if literal:  # the directions g_1, g_2
                g1, g2 = y[r, i, k] - x[r, i, k], yg[r, k] - x[r, i, k]
            else:
                g1 = g2 = ahead[k]
            if adapted:
                g1, g2 = _sgn(g1), _sgn(g2)
            uk = u[r, i, k]
            v = w * uk + (0.0 + (c1 * draws[0, i, k]) * g1 + (c2 * draws[1, i, k]) * g2)
            new[1, r, i, k] = v  # [2.1] / [3.11]
            new[2, r, i, k] = (v - uk) / dt if dt != 1.0 else v - uk  # [3.22] (/1: no bit)
            new[0, r, i, k] = x[r, i, k] + (dt * v if adapted else v)  # [3.10] / [2.2]
            buf[k] = v * v
            move |= v != 0.0
            big = _maximum(big, abs(v))
        if move:
            turned[r, i] = True
            for k in range(turn.shape[2]):
                turn[r, i, k] = new[1, r, i, k]
        top = _maximum(top, math.sqrt(0.0 + block_sum(buf, 0, d)))
    speeds[0, r], speeds[1, r] = top, big
    if not before:  # the velocity saw last tick's bests
        _bests(r, x, f, y, f_y, yg, best, maximise)


@kernel
def swarm_runs(lo: int, hi: int, x: np.ndarray, u: np.ndarray, y: np.ndarray, f_y: np.ndarray, f: np.ndarray,
               fn: int, states: np.ndarray, omegas: np.ndarray, cs: np.ndarray, ahead: np.ndarray, literal: bool,
               adapted: bool, dt: float, before: bool, maximise: bool, code: int, source: np.ndarray, scale: float,
               new: np.ndarray, yg: np.ndarray, best: np.ndarray, turn: np.ndarray, turned: np.ndarray,
               speeds: np.ndarray, bests: np.ndarray, track: int, tracked: np.ndarray) -> int:
    """``len(omegas)`` ticks of :func:`swarm_step` for runs ``lo … hi − 1`` in one call (for
    :meth:`Simulation.run`), with the coefficients ``omegas[j]`` and ``cs[j]`` (the same for
    every robot) at tick j, each run through all its ticks before the next, drawing its U(0,1)
    numbers itself from its own generator (PCG64's C
    function at address ``fn`` on the state at ``states[r]``) as one ``random((2, N, d))`` call a tick
    would: the same numbers, and the generator left where those calls leave it. Blocks of runs
    touch disjoint rows, so they may run in parallel threads (the kernel releases the GIL).
    The states alternate between ``new[0]`` and ``new[1]`` (each (3, R, N, d)); returns the
    index of the last. Per tick j: ``speeds[j]`` as in :func:`swarm_step`, ``bests[j]`` the
    runs' best fitness, ``tracked[j]`` the velocity of robot ``track`` of every run."""
    N, d = x.shape[1], x.shape[2]
    ticks = omegas.shape[0]
    draws, buf = np.empty((2, N, d)), np.empty(d)
    none2, none3 = np.empty((0, 0)), np.empty((0, 0, 0))
    for r in range(lo, hi):
        state = states[r]
        for j in range(ticks):
            for t in range(2):
                for i in range(N):
                    for k in range(d):
                        draws[t, i, k] = double_at(fn, state)
            xj = x if j == 0 else new[(j - 1) % 2, 0]
            uj = u if j == 0 else new[(j - 1) % 2, 1]
            out = new[j % 2]
            run_tick(r, xj, uj, y, f_y, f, draws, omegas[j], none2, cs[j], none3, ahead, literal, adapted, dt,
                     before, maximise, code, source, scale, out, yg, best, turn, turned, speeds[j], buf)
            bests[j, r] = best[r]
            for k in range(d):
                tracked[j, r, k] = out[1, r, track, k]
    return (ticks - 1) % 2
