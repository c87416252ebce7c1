"""Acoustic source localisation by a swarm (Rossides Ch. 7–8): one tick of the loop common to
A-, X-, B-, XB- and GT-PSO (§7.1–§8.1, pp. 148–174).

    listen → bests (strategy, forgetting) → velocity law → move → metrics

1. listen: hydrophone positions (one at the centre for A-/GT-PSO, bow and stern at ±D/2
   for X-/B-/XB-PSO; docs/readings.md, "Bow, stern and the sign of the lag") → band spectra
   (``signals.synthesise``, the default waveform mode) → intensity, and the two-hydrophone
   ``receiver.bearing`` (ρ, τ, α, rays) when the strategy needs it. ``mode="surrogate"`` draws the
   same statistics directly (``acoustics.surrogate``): APPROXIMATE, not in the thesis.
2. bests: ``strategy.update`` (A/X/B/XB/GT-PSO, forgetting a [7.2]/[7.9]/[8.6]) in ``_bests``,
   which also gives the attractor vectors (on SLO positions each robot decides in its own
   believed frame: ``acoustics.frames``).
3. velocity: ``adapted`` = Adapted PSO [3.11]/[3.10] in the global frame (Ch. 7: unbounded
   plane, kinematic, collisions ignored, heading = direction of u: docs/readings.md, "Heading of an omnidirectional
   robot"), tuned by
   β: ω = 1 − β, ĉ = βU/√2 [4.15]; ``nonomni`` = non-omnidirectional controller
   [8.7] = [5.13] with DVC [5.14]–[5.16] (Ch. 8): robots sense each other in six sectors
   (R_sense, robots as discs of ``robot_radius``), the global best is a ring obstacle of
   radius r_trap when escorting (``escort.with_escort``), energy limit [5.11]–[5.12], arc
   kinematics [5.5]–[5.10].
4. move; the source moves at v_s = v_n·U along ``source_heading`` [8.8].
5. metrics: CoM, |CoM − x_src|, converged at the first k with |CoM − x_src| ≤ d_c, the
   fraction of robots inside the ring of radius r_trap round the true source, the mean
   robot–source distance, and contacts.

Collisions are ignored, as in the thesis' kinematic runs: robots pass through each other
and nobody is disabled, but every step counts the robots whose discs touch another's
(``contacts``). All robots sense, decide and move together (simultaneous update).

Initialisation (docs/readings.md, "Initial state and partners"): f̂ = 0, y = x[0], u = 0;
robots uniform in a disc of radius d_0 round the origin (``start="source"``: round the source,
Fig. 8-5); headings U[0, 2π); the source at d_s = R_ref·10^(−SNR_0/20) on a uniformly random bearing (or a fixed one).

Runs are independent: run i draws everything from child i of ``SeedSequence(seed)`` in a
fixed order per step (initial layout; then per tick: spectra, partners, velocity draws), so
a run is the same alone or in a batch. With ``stop_on_converge`` a converged run is frozen
(masked out, shapes kept) and costs nothing more.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import Any, ClassVar, Literal

import numpy as np

from ..acoustics.band import Band
from ..acoustics.escort import moving_source, with_escort
from ..acoustics.forgetting import forget_update, improves
from ..acoustics.frames import in_own_frames
from ..acoustics.propagation import r_ref, snr_db, source_distance_for_snr
from ..acoustics.receiver import Bearing, bearing
from ..acoustics.signals import hydrophone_positions, intensity, synthesise
from ..acoustics.strategies import LocInfo, Sensed, Strategy, initial_memory, make_strategy
from ..acoustics.surrogate import surrogate
from ..acoustics.triangulation import Triangles
from ..core.contract import check_live
from ..core.positions import Oracle, PositionSource
from ..core.rng import run_generators
from ..core.schema import Column, Schema
from ..core.snapshot import SnapshotError, arrays, fields_of, from_fields, integer, part, rng_states, set_rng_states
from ..core.steering import SLACK, Steering
from ..pso.laws import adapted_velocity, motion_heading, reachable
from ..pso.tuning import from_beta, split
from ..robots.dvc import dvc_nonomni, forward_guard, w_max
from ..robots.laws import arc_pose_update, energy_limit, nonomni_velocity, to_body
from ..robots.sensing import SectorReading
from ..robots.swarm_sensing import contacts, pairwise, sense_robots

ControllerName = Literal["adapted", "nonomni"]
AcousticMode = Literal["waveform", "surrogate"]
Start = Literal["origin", "source"]


@dataclass(frozen=True)
class SonarParams:
    """Everything an acoustic swarm needs (defaults: Rossides Table 7.1, p. 160; Table 8.1,
    p. 180)."""

    algorithm: str = "xb-pso"  # a key of acoustics.strategies.STRATEGIES
    controller: ControllerName = "adapted"
    mode: AcousticMode = "waveform"
    snr0_db: float = 10.0  # SNR at the origin, sets d_s ([7.16], [7.17])
    psd_s_db: float = 120.0  # source PSD at 1 m, dB re 1 µPa²/Hz
    psd_n_db: float = 60.0  # noise PSD, dB re 1 µPa²/Hz
    f_c: float = 1000.0  # Hz
    Q: float = 1.5  # f_c/B [7.13]
    tbp: float = 100.0  # B·T
    c: float = 1500.0  # sound speed, m/s
    fs: float = 48_000.0  # sample rate of the lag grid (not in the thesis; docs/readings.md,
    # "The lag estimate and the sample rate (Chapter 7)")
    d_over_lambda: float = 0.5  # hydrophone separation D/λ_c
    full_lag: bool = False  # search the whole window, as MATLAB xcorr
    lag_peak: Literal["parabolic", "sample"] = "parabolic"  # refine τ_lag, or the sample lag of Alg. 5
    a: float = 1.0  # forgetting scale [7.2]
    d0: float = 50.0  # deployment radius, m
    dc: float = 50.0  # convergence radius, m
    U: float = 2.0  # top speed v_max, m/s
    dt: float = 1.0  # s
    beta: float = 0.9  # sensitivity β (ω = 1 − β)
    c1_share: float = 0.5  # c1/(c1 + c2)
    alpha_dvc: float = 0.9  # DVC safety factor (nonomni)
    sensing_range: float = 10.0  # R_sense, m (nonomni)
    robot_radius: float = 1.0  # disc round a 2 × 1 m hull, m (nonomni sensing, contacts)
    r_trap: float = 0.0  # escort ring radius, m (0: no escort)
    v_n: float = 0.0  # source speed / U [8.8]
    source_heading: float = 0.0  # rad, direction the source moves (thesis: +x)
    source_bearing: float | None = None  # rad from the origin; None = uniform random
    source: tuple[float, float] | None = None  # m, where the source starts (placed by hand); None = d_s on a bearing
    start: Start = "origin"
    guard: bool = False  # DVC forward guard (ours, not in the thesis): v ≤ α·sf_1/Δt
    stop_on_converge: bool = False

    def __post_init__(self) -> None:
        if self.controller not in ("adapted", "nonomni"):
            raise ValueError(f"controller: 'adapted' or 'nonomni', got {self.controller!r}")
        if self.mode not in ("waveform", "surrogate"):
            raise ValueError(f"mode: 'waveform' or 'surrogate', got {self.mode!r}")
        if self.mode == "surrogate" and self.full_lag:
            raise ValueError("full_lag: the surrogate mode has no correlation function")
        if self.lag_peak not in ("parabolic", "sample"):
            raise ValueError(f"lag_peak: 'parabolic' or 'sample', got {self.lag_peak!r}")
        if self.r_trap > 0 and self.controller != "nonomni":
            raise ValueError("r_trap: escorting needs the nonomni controller")
        if self.start not in ("origin", "source"):
            raise ValueError(f"start: 'origin' or 'source', got {self.start!r}")
        for name in ("U", "dt", "beta", "dc", "sensing_range", "robot_radius"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name}: must be > 0, got {getattr(self, name)!r}")
        if not self.d0 >= 0:
            raise ValueError(f"d0: must be >= 0, got {self.d0!r}")
        _ = self.band  # validates f_c, Q, tbp, c, fs

    @property
    def band(self) -> Band:
        return Band(f_c=self.f_c, Q=self.Q, tbp=self.tbp, c=self.c, fs=self.fs)

    @property
    def D(self) -> float:
        """Hydrophone separation D = (D/λ_c)·c/f_c, m."""
        return self.d_over_lambda * self.c / self.f_c

    @property
    def r_ref(self) -> float:
        """Range where the SNR is 0 dB [7.17], m."""
        return float(r_ref(self.psd_s_db, self.psd_n_db))

    @property
    def d_s(self) -> float:
        """Source distance from the origin giving SNR_0 ([7.16], [7.17]), m."""
        return float(source_distance_for_snr(self.snr0_db, self.r_ref))


@dataclass
class SonarState:
    """The swarms of every run at tick ``k`` (what the app and the recorder read)."""

    x: np.ndarray  # (R, N, 2) positions
    heading: np.ndarray  # (R, N) bow direction o, rad
    u: np.ndarray  # (R, N, 2) world velocity of the last move
    cmd: np.ndarray  # (R, N, 2) controller state: global u (adapted) or body [v, w] (nonomni)
    y: np.ndarray  # (R, N, 2) personal bests
    f_hat: np.ndarray  # (R, N) remembered fitness
    y_g: np.ndarray  # (R, 2) global best
    source: np.ndarray  # (R, 2) true source position now
    snr_db: np.ndarray  # (R, N) in-band SNR at each robot [7.16]
    status: np.ndarray  # (R, N) int8, always 0 (collisions ignored)
    steps: np.ndarray  # (R,) ticks each run has advanced (frozen runs stop counting)
    running: np.ndarray  # (R,) bool, still advancing
    first_converged: np.ndarray  # (R,) first k with |CoM − x_src| ≤ d_c, −1 if none yet
    k: int = 0
    intensity: np.ndarray | None = None  # (R', N, H) mean received power per hydrophone
    bearing: Bearing | None = None  # last receiver output (rays, corr, lags), two-hydrophone strategies
    loc: LocInfo | None = None  # last strategy decision (intersections, selected, triangles)
    reading: SectorReading | None = None  # last six-sector reading (nonomni)
    stepped: np.ndarray = field(default_factory=lambda: np.zeros(0, int))  # runs R' intensity…reading cover

    @property
    def best_fitness(self) -> np.ndarray:
        """(R,) largest remembered fitness of each run."""
        return self.f_hat.max(axis=1)


@dataclass(frozen=True)
class Decision:
    """Step 2 of a tick for the runs that advance: new memory, global best, the strategy's
    decision, the attractor vectors and the escort ring's centre."""

    f_hat: np.ndarray  # (R', N)
    y: np.ndarray  # (R', N, 2) personal bests
    y_g: np.ndarray  # (R', 2) global best
    loc: LocInfo
    g: np.ndarray  # (2, R', N, 2) vectors to the personal and the global best
    ring: np.ndarray  # (R', 2) y_g, or (R', N, 2) where each robot believes it is (SLO)


COLUMNS: Schema = (
    Column("com_x", "m", "float", "x of the swarm's centre of mass (CoM)"),
    Column("com_y", "m", "float", "y of the CoM"),
    Column("source_x", "m", "float", "x of the acoustic source"),
    Column("source_y", "m", "float", "y of the acoustic source"),
    Column("com_dist", "m", "float", "|CoM − source|"),
    Column("converged", "", "int", "1 once the CoM has come within d_c of the source, else 0"),
    Column("steps_to_converge", "", "int", "the first tick it did, −1 if none yet"),
    Column("frac_inside_ring", "", "float", "share of robots within the escort ring's radius of the source (0 "
                                            "without a ring)"),
    Column("mean_dist_to_source", "m", "float", "mean robot–source distance"),
    Column("contacts", "count", "int", "robots touching another (collisions are not enforced)"),
)


@dataclass
class SonarInfo:
    """Per-run metrics after a tick."""

    t: float
    com: np.ndarray  # (R, 2)
    com_dist: np.ndarray  # (R,) |CoM − x_src|
    converged: np.ndarray  # (R,) bool, reached d_c at some tick so far
    steps_to_converge: np.ndarray  # (R,) that first tick, −1 if none
    frac_inside_ring: np.ndarray  # (R,) robots with |x − x_src| < r_trap (0 without a ring)
    mean_dist_to_source: np.ndarray  # (R,)
    contacts: np.ndarray  # (R,) robots touching another (collisions are not enforced)
    source: np.ndarray  # (R, 2)
    running: np.ndarray  # (R,) bool

    def columns(self) -> dict[str, np.ndarray]:
        """CoM and source, their distance, convergence (flag and first tick, −1 if none), the share
        inside the escort ring, the mean robot–source distance and contacts."""
        return {"com_x": self.com[:, 0], "com_y": self.com[:, 1], "source_x": self.source[:, 0],
                "source_y": self.source[:, 1], "com_dist": self.com_dist, "converged": self.converged,
                "steps_to_converge": self.steps_to_converge, "frac_inside_ring": self.frac_inside_ring,
                "mean_dist_to_source": self.mean_dist_to_source, "contacts": self.contacts}


# SonarParams fields that shape the start (the source, the deployment) or the kind of swarm.
_FIXED = frozenset({"algorithm", "controller", "mode", "snr0_db", "d0", "start", "source_bearing", "source",
                    "full_lag", "stop_on_converge"})


class AcousticSwarm:
    """``runs`` seeded swarms of ``robots`` robots localising one acoustic source each.

    Implements :class:`~shoal.engine.core.contract.Engine`; :meth:`retune` takes the :class:`SonarParams` that
    shape the next listen or the next move (band, levels, forgetting, U, β, Δt, the escort ring,
    the source's motion, …) and, on SLO positions, the localisation keywords (``slo``)."""

    LIVE: ClassVar[frozenset[str]] = frozenset({f.name for f in fields(SonarParams)} - _FIXED | {"slo"})
    COLUMNS: ClassVar[Schema] = COLUMNS
    state: SonarState
    steering: Steering | None = None  # the next tick's command from outside the law (core/steering.py)

    def __init__(self, params: SonarParams | None = None, *, robots: int = 10, runs: int = 1, seed: int = 0,
                 first_run: int = 0, positions: PositionSource | None = None, compiled: bool = True) -> None:
        """``compiled`` False keeps the receiver's lag-grid correlation on numpy (the same bits)."""
        self.compiled = compiled
        if robots < 1 or runs < 1:
            raise ValueError("robots and runs must be >= 1")
        self.params = params or SonarParams()
        p = self.params
        self._tune()
        if self.strategy.hydrophones == 2 and p.mode == "waveform" and not p.D > 0:
            raise ValueError("d_over_lambda: must be > 0 for two hydrophones")
        if robots < self.strategy.min_robots:
            raise ValueError(f"{p.algorithm} needs at least {self.strategy.min_robots} robots")
        self.runs, self.first_run, self._robots = runs, first_run, robots
        self.positions: PositionSource = positions or Oracle()
        self.reset(seed)

    def _tune(self) -> None:
        """The band, the strategy and the controller's coefficients of ``params``."""
        p = self.params
        self.band = p.band
        self.strategy: Strategy = make_strategy(p.algorithm, a=p.a)
        tune = from_beta(p.dt, p.U, p.beta, d=2)  # ω = 1 − β, ĉ = βU/√2 [4.15]
        self.omega = tune.omega
        self.c = np.array(split(tune.c_hat, p.c1_share))  # c1, c2
        self.w_max = w_max(p.U, p.dt)  # min(√(4 e_max/π), π/(2Δt)) [5.12], Rossides §5.2, p. 114

    def retune(self, **changes: Any) -> list[str]:
        """Change :data:`LIVE` settings from the next tick on, keeping the swarm and its memory;
        returns the names that changed. A new source speed, heading, U or Δt lets the source
        carry on from where it is. Refused (``ValueError``, nothing changed) for other keywords."""
        check_live(self.LIVE, changes)
        slo = changes.pop("slo", None)
        old, params = self.params, replace(self.params, **changes)  # validates
        changed = [k for k in changes if getattr(params, k) != getattr(old, k)]
        if slo:
            self.positions.retune(**slo)
            changed.append("slo")
        if {"v_n", "source_heading", "U", "dt"} & set(changed):
            self._restart_source_motion(params)
        self.params = params
        self._tune()
        self._refresh(np.arange(self.runs))
        return changed

    def _restart_source_motion(self, params: SonarParams) -> None:
        """A moving source under new ``params`` carries on from where it is now [8.8]."""
        h = params.source_heading
        step = np.array([np.cos(h), np.sin(h)]) * params.v_n * params.U * params.dt
        self.source0 = self.state.source - self.state.steps[:, None] * step

    # ------------------------------------------------------------------ setup
    @property
    def dt(self) -> float:
        return self.params.dt

    @property
    def t(self) -> float:
        return self.state.k * self.dt

    @property
    def robots(self) -> int:
        return self._robots

    @property
    def running(self) -> np.ndarray:
        return self.state.running

    def reset(self, seed: int | None = None) -> None:
        """Start again from step 0 with ``seed`` (or the current one)."""
        if seed is not None or not hasattr(self, "seed"):
            self.seed = int(seed or 0)
        p, N = self.params, self._robots
        self.rngs = run_generators(self.seed, self.first_run, self.runs)
        self.steering = None
        x = np.empty((self.runs, N, 2))
        heading = np.empty((self.runs, N))
        bearing0 = np.empty(self.runs)
        for r, g in enumerate(self.rngs):  # fixed draw order per run: docs/readings.md, "Initial state and partners"
            rad = p.d0 * np.sqrt(g.random(N))
            ang = 2.0 * np.pi * g.random(N)
            x[r] = np.stack([rad * np.cos(ang), rad * np.sin(ang)], axis=-1)
            heading[r] = 2.0 * np.pi * g.random(N)
            bearing0[r] = 2.0 * np.pi * g.random() if p.source_bearing is None else p.source_bearing
        self.source0 = p.d_s * np.stack([np.cos(bearing0), np.sin(bearing0)], axis=-1)  # d_s on a bearing
        if p.source is not None:  # placed by hand (the bearing is still drawn: the same draws follow)
            self.source0[:] = p.source
        if p.start == "source":
            x = x + self.source0[:, None, :]
        f_hat, y = initial_memory(x)
        R = self.runs
        self.state = SonarState(
            x=x, heading=heading, u=np.zeros_like(x), cmd=np.zeros_like(x), y=y, f_hat=f_hat,
            y_g=x.mean(axis=1), source=self.source0.copy(), snr_db=np.zeros((R, N)),
            status=np.zeros((R, N), np.int8), steps=np.zeros(R, int), running=np.ones(R, bool),
            first_converged=np.full(R, -1),
        )
        self._refresh(np.arange(R))
        self._converge(np.arange(R))
        s = self.state
        self.positions.start(s.x, s.y, s.k, self.seed, self.first_run)

    # ------------------------------------------------------------------ pieces
    def _listen(self, x: np.ndarray, heading: np.ndarray, src: np.ndarray,
                rngs: list) -> tuple[Sensed, np.ndarray, Bearing | None]:
        """Step 1 for runs with positions ``x`` (R', N, 2): the Sensed arrays, the per-hydrophone
        intensity and (two hydrophones) the receiver output."""
        p, strat = self.params, self.strategy
        two = strat.hydrophones == 2
        pos = hydrophone_positions(x, heading, p.D if two else None)  # bow and stern
        if p.mode == "surrogate":  # APPROXIMATE: docs/readings.md, "The fast surrogate receiver (ours)"
            sr = surrogate(rngs, pos, src, self.band, p.r_ref, heading=heading if two else None, D=p.D if two else None,
                           refine=p.lag_peak == "parabolic")
            power, b = sr.intensity, sr.bearing
        else:
            spectra = synthesise(rngs, pos, src, self.band, p.r_ref)  # [7.13]–[7.17] in normalised units
            power = intensity(spectra)  # f_A ≈ I + N [7.1]
            b = bearing(spectra, self.band, p.D, heading, full_lag=p.full_lag, refine=p.lag_peak == "parabolic",
                        compiled=self.compiled) if two else None  # [6.9]–[7.7]
        sensed = Sensed(
            intensity=power.mean(axis=-1) if "intensity" in strat.needs else None,
            rho=b.rho if b is not None and "rho" in strat.needs else None,  # ρ [7.5]
            rays=b.rays if b is not None and "rays" in strat.needs else None,  # [7.7]
        )
        return sensed, power, b

    def _bests(self, idx: np.ndarray, x: np.ndarray, sensed: Sensed, rngs: list) -> Decision:
        """Step 2 for runs ``idx`` at positions ``x``: the strategy's memory and global best,
        and the attractor vectors. On true positions the strategy decides once for the swarm."""
        s = self.state
        if not self.positions.exact:
            return self._believed_bests(idx, x, sensed, rngs)
        f_hat, y, yg, loc = self.strategy.update(s.f_hat[idx], s.y[idx], x, sensed, rngs)
        return Decision(f_hat, y, yg, loc, np.stack([y - x, yg[:, None, :] - x]), yg)

    def _believed_bests(self, idx: np.ndarray, x: np.ndarray, sensed: Sensed, rngs: list) -> Decision:
        """Step 2 on SLO positions: every robot decides in its own believed frame
        (:func:`~shoal.engine.acoustics.frames.in_own_frames`), keeps its personal best relative
        to itself with the forgetting rule [7.2]/[7.9]/[8.6] on the candidate's offset, and heads
        for the global best as it places it: the best robot's x̂_i,owner + P_owner (A-/X-PSO) or
        the centroid of x̂_ij + P_j [7.11]. ``y`` is then x_i + P_i and ``y_g`` the swarm's own
        version of the global best (the owner's x + P, or the centroid of x + P)."""
        s, strat, pos = self.state, self.strategy, self.positions
        pos.observe(s.x, s.k - 1)  # done at the end of the last tick (the counter moved on since)
        mine = in_own_frames(strat, s.f_hat[idx], pos.placed(s.x)[idx], sensed, rngs)
        offset = mine["candidate"] - x  # the candidate as seen from the robot
        f_old = s.f_hat[idx]
        better = improves(f_old, mine["fitness"], offset, mine["valid"])
        f_hat, pbest = forget_update(f_old, pos.to_personal(s.x, s.y)[idx], mine["fitness"], offset, mine["valid"],
                                     strat.a)
        stepped, at = np.zeros(s.f_hat.shape, bool), np.zeros(s.x.shape)
        stepped[idx], at[idx] = True, pbest
        pos.keep(stepped, at)  # the runs that advance: their bests after forgetting
        y = x + pbest
        f_all = s.f_hat.copy()
        f_all[idx] = f_hat
        to_g = self._to_global(f_all)[idx]
        f_g = None
        if strat.global_best == "best":
            owner = np.argmax(f_hat, axis=1)
            y_g, f_g = y[np.arange(len(idx)), owner], f_hat[np.arange(len(idx)), owner]
        else:
            y_g = y.mean(axis=1)
        loc = LocInfo(improved=better, f_g=f_g, **mine)
        return Decision(f_hat, y, y_g, loc, np.stack([pbest, to_g]), x + to_g)

    def _to_global(self, f_hat: np.ndarray) -> np.ndarray:
        """Each robot's vector to the global best as it knows it, from the memory ``f_hat`` (R, N):
        the best robot's personal best (A-/X-PSO) or the centroid of all of them [7.11]."""
        s = self.state
        if self.strategy.global_best == "best":
            return self.positions.to_owner(s.x, s.y, np.argmax(f_hat, axis=1))
        return self.positions.to_centroid(s.x, s.y)

    def believed_gbest(self) -> np.ndarray:
        """(R, N, 2) where each robot believes the global best is."""
        return self.state.x + self._to_global(self.state.f_hat)

    def _adapted(self, idx: np.ndarray, x: np.ndarray, g: np.ndarray, rngs: list, steering: Steering | None = None):
        """Adapted PSO [3.11], [3.10] towards the attractor vectors ``g`` (2, R', N, 2);
        heading = direction of u (docs/readings.md, "Heading of an omnidirectional robot").
        Steered: ω, c or the velocity given (within the law's reachable set)."""
        s, N = self.state, self._robots
        r = np.stack([gen.random((2, N, 2)) for gen in rngs], axis=1)  # r1, r2 per component
        omega, c = (self.omega, self.c) if steering is None else steering.coefficients(self.omega, self.c, x.shape[:2])
        u = adapted_velocity(s.cmd[idx], g, c, omega, r)  # [3.11]
        if steering is not None and steering.velocity is not None:
            u = reachable(np.asarray(steering.velocity, dtype=float), s.cmd[idx], c, omega)
        x_new = x + self.dt * u  # [3.10]
        return x_new, motion_heading(u, s.heading[idx]), u, u, None

    def _nonomni(self, idx: np.ndarray, x: np.ndarray, g: np.ndarray, ring: np.ndarray, rngs: list, pair,
                 steering: Steering | None = None):
        """Non-omni controller [8.7] = [5.13] with DVC [5.14]–[5.16], ring obstacle round
        ``ring`` (y_g), energy limit; attractor vectors ``g`` (2, R', N, 2). Steered: ω, c or the
        command [v, w] given (forward only, within the energy limit)."""
        p, s, N = self.params, self.state, self._robots
        o = s.heading[idx]
        reading = sense_robots(x, o, robot_radius=p.robot_radius, sensing_range=p.sensing_range, pair=pair)
        if p.r_trap > 0:  # Ch. 8.2: y_g as a ring obstacle of radius r_trap
            reading = with_escort(reading, x, o, ring, p.r_trap, sensing_range=p.sensing_range)
        omega, c = dvc_nonomni(reading.gap, alpha=p.alpha_dvc, beta=p.beta, dt=p.dt, sensing_range=p.sensing_range,
                               w_max=self.w_max, c1_share=p.c1_share, v_max=p.U)
        if steering is not None:
            omega, c = steering.coefficients(omega, c, x.shape[:2])  # type: ignore[assignment]
        r = np.stack([gen.random((5, N)) for gen in rngs], axis=1)  # r1..r5
        vw = nonomni_velocity(s.cmd[idx], to_body(g[0], o), to_body(g[1], o), c, omega, r)  # [5.13]
        v, w = energy_limit(vw[..., 0], vw[..., 1], p.U)  # [5.11], [5.12]
        if steering is not None and steering.velocity is not None:  # the law's draws are made all the same
            given = np.asarray(steering.velocity, dtype=float)
            v, w = energy_limit(np.maximum(given[..., 0], 0.0), given[..., 1], p.U, slack=SLACK)
        if p.guard:
            v = forward_guard(v, reading.gap, alpha=p.alpha_dvc, dt=p.dt)
        x_new, o_new = arc_pose_update(x, o, v, w, p.dt)  # [5.5]–[5.10]
        return x_new, o_new, (x_new - x) / p.dt, np.stack([v, w], axis=-1), reading

    def _refresh(self, idx: np.ndarray) -> None:
        """SNR at every robot of runs ``idx`` [7.16]."""
        s, p = self.state, self.params
        s.snr_db[idx] = snr_db(np.linalg.norm(s.x[idx] - s.source[idx, None, :], axis=-1), p.psd_s_db, p.psd_n_db)

    def _converge(self, idx: np.ndarray) -> None:
        """Record the first tick with |CoM − x_src| ≤ d_c (Rossides §7.3.2, p. 161; docs/readings.md,
        "How convergence is declared (Chapter 7)"); freeze if asked."""
        s = self.state
        d = np.linalg.norm(s.x[idx].mean(axis=1) - s.source[idx], axis=-1)
        new = (s.first_converged[idx] < 0) & (d <= self.params.dc)
        s.first_converged[idx[new]] = s.steps[idx[new]]
        if self.params.stop_on_converge:
            s.running[idx[new]] = False

    # ------------------------------------------------------------------ tick
    def step(self) -> SonarInfo:
        """Advance every running run by one tick Δt (steered by :attr:`steering`, if set)."""
        s = self.state
        steering, self.steering = self.steering, None
        idx = np.flatnonzero(s.running)
        s.k += 1
        if idx.size:
            self._advance(idx, None if steering is None else steering.runs(idx))
        self.positions.observe(s.x, s.k)  # where the moves ended: current beliefs for drawing
        return self.info()

    def _advance(self, idx: np.ndarray, steering: Steering | None = None) -> None:
        """The tick of the running runs ``idx`` (``steering``: theirs)."""
        p, s = self.params, self.state
        rngs = [self.rngs[i] for i in idx]
        x, src = s.x[idx], s.source[idx]
        sensed, power, b = self._listen(x, s.heading[idx], src, rngs)  # 1 listen
        d = self._bests(idx, x, sensed, rngs)  # 2 bests
        if p.controller == "adapted":  # 3 velocity, 4 move
            x_new, o_new, u, cmd, reading = self._adapted(idx, x, d.g, rngs, steering)
        else:
            x_new, o_new, u, cmd, reading = self._nonomni(idx, x, d.g, d.ring, rngs, pairwise(x), steering)
        s.x[idx], s.heading[idx], s.u[idx], s.cmd[idx] = x_new, o_new, u, cmd
        s.y[idx], s.f_hat[idx], s.y_g[idx] = d.y, d.f_hat, d.y_g
        s.steps[idx] += 1
        if p.v_n > 0:  # [8.8]
            s.source[idx] = moving_source(self.source0[idx], p.source_heading, p.v_n, p.U, p.dt, s.steps[idx])
        s.intensity, s.bearing, s.loc, s.reading, s.stepped = power, b, d.loc, reading, idx
        self._refresh(idx)  # 5 metrics
        self._converge(idx)

    # ------------------------------------------------------------------ snapshot
    STATE = ("x", "heading", "u", "cmd", "y", "f_hat", "y_g", "source", "snr_db", "status", "steps", "running",
             "first_converged", "stepped")

    def snapshot(self) -> dict[str, Any]:
        """Everything the runs depend on beyond the settings they were built with, as plain data
        (:mod:`~shoal.engine.core.snapshot`): the swarms, their memories, the source (where it
        started its motion too), every generator, and the last tick's hearing and decisions."""
        s = self.state
        state: dict[str, Any] = {n: np.array(getattr(s, n)) for n in self.STATE}
        state["intensity"] = None if s.intensity is None else np.array(s.intensity)
        state["bearing"] = None if s.bearing is None else fields_of(s.bearing)
        state["loc"] = None if s.loc is None else fields_of(s.loc, nested=("triangles",))
        state["reading"] = None if s.reading is None else fields_of(s.reading)
        return {"k": s.k, "seed": self.seed, "state": state, "source0": self.source0.copy(),
                "rngs": rng_states(self.rngs), "positions": self.positions.snapshot()}

    def restore(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`snapshot`'s ``data`` (of a swarm built with the same settings and runs)."""
        st = part(data, "state")
        got: dict[str, Any] = {n: arrays(part(st, n, "state"), f"state.{n}") for n in self.STATE}
        R, N = self.runs, self._robots
        for n in self.STATE:
            want = {"x": (R, N, 2), "u": (R, N, 2), "cmd": (R, N, 2), "y": (R, N, 2), "y_g": (R, 2), "source": (R, 2),
                    "steps": (R,), "running": (R,), "first_converged": (R,)}.get(n, (R, N))
            if n != "stepped" and got[n].shape != want:
                raise SnapshotError(f"state.{n}: expected shape {want}, got {got[n].shape}")
        got["status"] = got["status"].astype(np.int8)
        got["running"] = got["running"].astype(bool)
        v = part(st, "intensity", "state")
        got["intensity"] = None if v is None else arrays(v, "state.intensity")
        for name, cls in (("bearing", Bearing), ("loc", LocInfo), ("reading", SectorReading)):
            v = part(st, name, "state")
            if v is not None:
                v = {k: (arrays(a, f"state.{name}.{k}") if isinstance(a, np.ndarray) else a) for k, a in v.items()}
                tri = v.get("triangles") if name == "loc" else None
                if tri is not None:
                    v["triangles"] = from_fields(Triangles, {k: arrays(a, f"state.loc.triangles.{k}")
                                                            for k, a in tri.items()}, "state.loc.triangles")
            got[name] = None if v is None else from_fields(cls, v, f"state.{name}")
        source0 = arrays(part(data, "source0"), "source0", dtype=np.floating)
        if source0.shape != (R, 2):
            raise SnapshotError(f"source0: expected shape {(R, 2)}, got {source0.shape}")
        k, seed = integer(part(data, "k"), "k"), integer(part(data, "seed"), "seed")
        set_rng_states(self.rngs, part(data, "rngs"), "rngs")
        self.positions.restore(part(data, "positions"), got["x"])
        self.seed, self.source0 = seed, source0
        self.state = SonarState(**got, k=k)

    def info(self) -> SonarInfo:
        """Metrics of the current state."""
        p, s = self.params, self.state
        com = s.x.mean(axis=1)
        dist = np.linalg.norm(s.x - s.source[:, None, :], axis=-1)
        inside = (dist < p.r_trap).mean(axis=1) if p.r_trap > 0 else np.zeros(self.runs)
        return SonarInfo(
            t=self.t, com=com, com_dist=np.linalg.norm(com - s.source, axis=-1), converged=s.first_converged >= 0,
            steps_to_converge=s.first_converged.copy(), frac_inside_ring=inside, mean_dist_to_source=dist.mean(axis=1),
            contacts=contacts(pairwise(s.x)[1], p.robot_radius), source=s.source.copy(), running=s.running.copy(),
        )


def straight_line_steps(params: SonarParams) -> float:
    """Lower bound (d_s − d_c)/(U·Δt) on the ticks to converge (a straight run at full speed)."""
    return max(params.d_s - params.dc, 0.0) / (params.U * params.dt)


__all__ = ["AcousticSwarm", "SonarInfo", "SonarParams", "SonarState", "straight_line_steps"]
