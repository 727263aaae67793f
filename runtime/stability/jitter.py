"""A jitter budget that is sufficient: stability for every sequence of sampling periods and
latencies within stated ranges, proved by a common quadratic Lyapunov function.

The loop of :mod:`runtime.stability.sampled_loop`, with the plant's sampling period h_k and
the latency D_k of the command computed at t_k varying from sample to sample within
[h_min, h_max] × [D_min, D_max] (the law keeps its configured h; D_k < h_k, one command in
flight, the one before applied until t_k + D_k), is a switched system z_{k+1} = J(h_k, D_k)
z_k about the steady motion of the nominal timing. A constant-timing spectral radius below
1 at every (h, D) is necessary, not sufficient (a switched system can diverge with every
mode stable). Sufficient: a P ≻ 0 with ‖J(h, D)‖_P < 1 for every (h, D) in the range, the
P-norm ‖A‖_P = ‖P^½ A P^-½‖₂; then V = zᵀPz decreases at every sample whatever the
sequence.

Method. J is computed on a grid of the range (``GRID`` points per varying axis), reduced
to the loop states less the modes every J keeps at exactly 1 (a conserved odometric
combination, a held gain: a constant offset, neither growing nor decaying, as the
analysis reports apart). An SDP (cvxpy, Clarabel) finds P with I ⪯ P ⪯ κ I and
J_iᵀ P J_i ⪯ γ² P at every grid point, γ < 1 as small as it goes, κ as small as it goes
for that γ; the solver's P is checked against every inequality, not trusted. Between grid
points J(h, D) = J_i + Δ with ‖Δ‖_P ≤ δ_i, a bound derived from the loop's structure
(:mod:`runtime.stability.gap`: the plant's rows are the zero-order-hold flow of its
continuous linearisation, e^{Ah} and ∫ e^{As} ds B, every other row independent of the
timing; δ_i = L_h Δh/2 + L_D ΔD/2 with L_h, L_D sups of ‖e^{As} R‖ over the cell, at most
E (a + b (k + 2)) and E b (k + 1), a = ‖A‖, b = ‖B‖, k = ‖K‖ the law's Jacobian,
E = e^{a h_max}), so ‖J‖_P ≤ max_i (‖J_i‖_P + δ_i) everywhere in the range. The verdict:
"proved" when that bound is < 1; "unstable" when some constant timing in the range has a
spectral radius ≥ 1 (or a switching sequence found by :func:`adversarial` grows); else
"not proved (necessary condition holds)", with the reason: no common P at the grid points,
the margin not covering the gap bound, or a structure the gap bound cannot take (then no
bound is derived and nothing is proved: :class:`runtime.stability.gap.NoGapBound`).

Assumptions (stated with every verdict): the linearisation about the nominal steady
motion (a period that differs from the law's h also forces the loop: the reference's
time base; a bounded disturbance where the linear part is proved stable), the
experiment's plant, sensing and configuration, D_max < h_min; for the gap bound, the plant's
flow and not its RK4 steps (the computed rows match the flow within the stated mismatch m,
2m added to δ).
"""

from __future__ import annotations

import itertools
import math
import time
import warnings
from dataclasses import dataclass, replace

import cvxpy as cp
import numpy as np
from numpy.typing import NDArray
from scipy.linalg import null_space, sqrtm

from runtime.bindings.generated import RobotCode
from runtime.experiment.settings import Experiment
from runtime.plants import plant_for
from runtime.sim import loop as closed_loop
from runtime.sim import paths
from runtime.sim.timing import GivenTiming
from runtime.stability.gap import NoGapBound, ZohRows, cells, check_reduction, gap_bounds, zoh_rows
from runtime.stability.sampled_loop import ClosedLoop, LoopSetting, loop_states, max_delay
from runtime.stability.verification import diverged, linear_experiment

Matrix = NDArray[np.float64]
GRID = (9, 5)  # points on the varying axis of a range that varies in one, per axis in two
NEUTRAL = 1e-7  # a mode every J keeps at 1 within this
# Growth per sample within this of 1 is neutral, not divergence (as the analysis'
# NEUTRAL_TOL: a mode that a finite-difference Jacobian puts at 1 ± 1e-7 is an offset)
GROWTH_TOL = 1e-6
SLACK = 1e-4  # the SDP is solved for γ (1 − SLACK) so that its P passes the exact check at γ


@dataclass(frozen=True)
class Timing:
    """The ranges of the plant's sampling period and of the latency (s)."""

    h_min: float
    h_max: float
    d_min: float
    d_max: float

    def describe(self) -> str:
        ms = 1e3
        return (f"h in [{self.h_min * ms:.4g}, {self.h_max * ms:.4g}] ms, latency in "
                f"[{self.d_min * ms:.4g}, {self.d_max * ms:.4g}] ms")


def delay_jitter(h: float, delay: float, jitter: float) -> Timing:
    """``[controller] jitter``: every latency within ± ``jitter`` of ``delay`` (not below 0),
    the period h."""
    return Timing(h, h, max(0.0, delay - jitter), delay + jitter)


def measured(mean_period: float, worst_period: float, worst_latency: float) -> Timing:
    """The measured form a ros2_control user has: periods within ± (worst − mean) of the
    mean (at least a tenth of it), latencies in [0, worst latency]."""
    spread = max(0.0, worst_period - mean_period)
    return Timing(max(0.1 * mean_period, mean_period - spread), mean_period + spread,
                  0.0, worst_latency)


@dataclass(frozen=True)
class Family:
    """J on the grid of a timing range, reduced (see the module docstring), with the ZOH
    structure the gap bound rests on (:mod:`runtime.stability.gap`), or why there is none."""

    timing: Timing
    hs: tuple[float, ...]
    ds: tuple[float, ...]
    mats: tuple[Matrix, ...]  # row-major over (h, D)
    radius: float  # the largest constant-timing spectral radius on the grid
    basis: Matrix  # the reduced coordinates: J_red = basisᵀ J basis on the loop states
    zoh: ZohRows | None  # None: no derived gap bound, for the reason ``no_bound``
    no_bound: str = ""

    def gaps(self, p: Matrix) -> list[float]:
        """δ_i per grid point: the derived bound on ‖J − J_i‖_P over its cell
        (:func:`runtime.stability.gap.gap_bounds`)."""
        assert self.zoh is not None, self.no_bound
        return gap_bounds(self.zoh, self.basis, p, cells(self.hs, self.ds))


def grid(lo: float, hi: float, n: int) -> tuple[float, ...]:
    return (lo,) if hi - lo < 1e-12 else tuple(float(x) for x in np.linspace(lo, hi, n))


def loop_for(s: LoopSetting, tail: int = 20) -> ClosedLoop:
    """The loop with one command in flight kept in its state (the latency can vary)."""
    return ClosedLoop(replace(s, in_flight=max(1, s.in_flight)), tail)


@dataclass(frozen=True)
class Reduction:
    """The quotient of :func:`reduce`: J_red = basisᵀ J basis; ``left`` the common left
    invariants and ``fixed`` the common fixed vectors removed (columns, on the loop states)."""

    basis: Matrix
    left: Matrix
    fixed: Matrix
    inner: Matrix  # the coordinates after the first step, where ``fixed`` is found


def reduction(mats: list[Matrix]) -> Reduction:
    """The maps on the quotient by every mode all of them keep at 1: restricted to the
    kernel of their common left invariants, then modulo their common fixed vectors."""
    n = len(mats[0])
    left = null_space(np.vstack([(m - np.eye(n)).T for m in mats]), rcond=NEUTRAL)
    basis = null_space(left.T) if left.size else np.eye(n)
    inner = [basis.T @ m @ basis for m in mats]
    k = len(inner[0])
    fixed = null_space(np.vstack([m - np.eye(k) for m in inner]), rcond=NEUTRAL)
    if fixed.size:
        return Reduction(basis @ null_space(fixed.T), left, basis @ fixed, basis)
    return Reduction(basis, left, np.zeros((n, 0)), basis)


def reduce(mats: list[Matrix]) -> list[Matrix]:
    """The maps on the quotient (:func:`reduction`)."""
    w = reduction(mats).basis
    return [w.T @ m @ w for m in mats]


def family(loop: ClosedLoop, gain: float, timing: Timing) -> Family:
    both = timing.h_max > timing.h_min and timing.d_max > timing.d_min
    n = GRID[1] if both else GRID[0]
    hs, ds = grid(timing.h_min, timing.h_max, n), grid(timing.d_min, timing.d_max, n)
    if timing.d_max >= timing.h_min:
        raise ValueError(f"the jitter model needs the latency below the period: "
                         f"{timing.describe()}")
    full = [loop.timed_jacobian(gain, h, d) for h in hs for d in ds]
    eta = loop.sl["plant_eta"]
    states = loop_states(np.sum([np.abs(m) for m in full], axis=0), range(eta.start, eta.stop))
    ix = np.ix_(states, states)
    on_states = [m[ix] for m in full]
    red = reduction(on_states)
    mats = [red.basis.T @ m @ red.basis for m in on_states]
    radius = max(float(np.abs(np.linalg.eigvals(m)).max()) for m in mats)
    zoh: ZohRows | None = None
    why = ""
    try:
        zoh = zoh_rows(loop, states, hs, ds, full)
        if len(mats) > 1:  # a single timing has no gaps to cover
            check_reduction(zoh, red.left, red.inner, red.fixed, len(hs) > 1)
    except NoGapBound as exc:
        zoh, why = None, f"no derived gap bound: {exc}"
    return Family(timing, hs, ds, tuple(mats), radius, red.basis, zoh, why)


def lyapunov(mats: tuple[Matrix, ...], gamma: float) -> tuple[float, Matrix] | None:
    """(κ, P): P with I ⪯ P ⪯ κ I and AᵀPA ⪯ γ² P for every A, κ smallest; None if the
    SDP finds none."""
    n = len(mats[0])
    p = cp.Variable((n, n), symmetric=True)
    kappa = cp.Variable()
    cons = [p >> np.eye(n), p << kappa * np.eye(n)]
    tight = (gamma * (1.0 - SLACK)) ** 2  # solved with slack, checked without it
    cons += [a.T @ p @ a << tight * p for a in mats]
    prob = cp.Problem(cp.Minimize(kappa), cons)
    try:
        with warnings.catch_warnings():  # an inaccurate solution is checked below
            warnings.simplefilter("ignore", UserWarning)
            prob.solve(solver=cp.CLARABEL)
    except cp.SolverError:
        return None
    if prob.status not in ("optimal", "optimal_inaccurate") or p.value is None:
        return None
    pv = 0.5 * (p.value + p.value.T)
    eig = np.linalg.eigvalsh(pv)
    # checked, not trusted: the solver's P satisfies every inequality
    for a in mats:
        if np.linalg.eigvalsh(a.T @ pv @ a - gamma**2 * pv).max() > 0.0:
            return None
    return float(eig.max() / eig.min()), pv


@dataclass(frozen=True)
class Proof:
    """What the SDP found and what covers the gaps: the largest ‖J_i‖_P at the grid points
    (exact, ≤ the SDP's γ), P's condition number κ, the largest derived gap bound δ_i
    (P-norm, :mod:`runtime.stability.gap`) and the bound on ‖J‖_P over the whole range,
    max_i (‖J_i‖_P + δ_i); ``delta`` and ``bound`` are inf where no gap bound is derived."""

    gamma: float
    kappa: float
    delta: float
    bound: float


def p_norm(a: Matrix, p: Matrix) -> float:
    root = np.real(sqrtm(p))
    return float(np.linalg.norm(root @ a @ np.linalg.inv(root), 2))


def covered(fam: Family, p: Matrix, kappa: float) -> Proof:
    """The bound on ‖J‖_P over the range with ``p``: each grid point's own ‖J_i‖_P plus
    its cell's gap bound (inf without a derived bound)."""
    norms = [p_norm(m, p) for m in fam.mats]
    if fam.zoh is None:
        return Proof(max(norms), kappa, math.inf, math.inf)
    gaps = fam.gaps(p)
    return Proof(max(norms), kappa, max(gaps),
                 max(n + g for n, g in zip(norms, gaps, strict=True)))


def prove(fam: Family) -> Proof | None:
    """The best bound over a few γ between the smallest feasible and 1 (None: no common
    P at the grid points)."""
    lo, hi = 0.0, 1.0
    if lyapunov(fam.mats, hi - 1e-9) is None:
        return None
    for _ in range(14):  # the smallest γ with a common P
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if lyapunov(fam.mats, mid) is not None else (mid, hi)
    best: Proof | None = None
    for gamma in np.linspace(hi, 1.0, 6)[:-1]:
        found = lyapunov(fam.mats, float(gamma) * (1 + 1e-6))
        if found is not None:
            proof = covered(fam, found[1], found[0])
            if best is None or (proof.bound, proof.gamma) < (best.bound, best.gamma):
                best = proof
    return best


@dataclass(frozen=True)
class Search:
    """The worst growth rate per sample an adversarial switching search found, and its
    sequence of (h, D)."""

    rate: float
    sequence: tuple[tuple[float, float], ...]


def adversarial(loop: ClosedLoop, gain: float, timing: Timing, length: int = 6,
                steps: int = 60) -> Search:
    """Worst-case switching between the range's extreme periods and latencies: every
    periodic pattern of the corners up to ``length`` samples (the spectral radius of the
    product, per sample), then a greedy search that picks, sample by sample, the corner
    that grows ‖z‖ most (from random directions), its word judged as repeated: the
    spectral radius of its product, per sample."""
    corners = sorted({(h, d) for h in (timing.h_min, timing.h_max)
                      for d in (timing.d_min, timing.d_max)})
    full = [loop.timed_jacobian(gain, h, d) for h, d in corners]
    eta = loop.sl["plant_eta"]
    states = loop_states(np.sum([np.abs(m) for m in full], axis=0), range(eta.start, eta.stop))
    ix = np.ix_(states, states)
    mats = reduce([m[ix] for m in full])
    best = Search(0.0, ())
    for n in range(1, length + 1):
        for word in itertools.product(range(len(mats)), repeat=n):
            if word[0] != min(word):  # a rotation of a word already tried
                continue
            prod = np.eye(len(mats[0]))
            for i in word:
                prod = mats[i] @ prod
            rate = float(np.abs(np.linalg.eigvals(prod)).max()) ** (1.0 / n)
            if rate > best.rate:
                best = Search(rate, tuple(corners[i] for i in word))
    rng = np.random.default_rng(46)
    for _ in range(4):
        z = rng.standard_normal(len(mats[0]))
        z /= np.linalg.norm(z)
        greedy: list[int] = []
        prod = np.eye(len(mats[0]))
        for _ in range(steps):
            nxt = [m @ z for m in mats]
            i = int(np.argmax([np.linalg.norm(v) for v in nxt]))
            z = nxt[i] / max(float(np.linalg.norm(nxt[i])), 1e-300)
            greedy.append(i)
            prod = mats[i] @ prod
        # the greedy word repeated: its asymptotic growth (a finite run's norm growth would
        # count a non-normal map's transient as divergence)
        rate = float(np.abs(np.linalg.eigvals(prod)).max()) ** (1.0 / steps)
        if rate > best.rate:
            best = Search(rate, tuple(corners[i] for i in greedy))
    return best


@dataclass(frozen=True)
class JitterVerdict:
    """The verdict for one timing range, with what it rests on: the constant-timing radius,
    the bound on ‖J‖_P over the range (γ + δ; None: no common P at the grid points), the
    derived gap bound δ (P-norm), and why a verdict that is not "proved" is not."""

    timing: Timing
    verdict: str  # "proved", "not proved (necessary condition holds)" or "unstable"
    radius: float  # the largest constant-timing spectral radius on the grid
    bound: float | None
    search: Search | None = None
    delta: float | None = None
    reason: str = ""
    margin: float | None = None  # the largest ‖J_i‖_P at the grid points (the SDP's)
    mismatch: float | None = None  # m: the computed plant rows against their ZOH flow

    def describe(self) -> str:
        """The verdict with what it rests on, one line."""
        out = f"{self.verdict} (constant-timing radius ≤ {self.radius:.3f}"
        if self.bound is not None and math.isfinite(self.bound):
            out += (f", ‖J‖_P ≤ {self.bound:.3f} over the range, derived gap bound "
                    f"δ ≤ {self.delta:.3g}, ZOH model mismatch m = {self.mismatch:.2g}")
        return out + (f"; {self.reason})" if self.reason else ")")


def verdict(loop: ClosedLoop, gain: float, timing: Timing, search: bool = False
            ) -> JitterVerdict:
    fam = family(loop, gain, timing)
    found = adversarial(loop, gain, timing) if search else None
    if fam.radius >= 1.0 + GROWTH_TOL or (found is not None and found.rate >= 1.0 + GROWTH_TOL):
        why = ("a constant timing in the range has spectral radius ≥ 1"
               if fam.radius >= 1.0 + GROWTH_TOL
               else "the adversarial search found a growing switching sequence")
        return JitterVerdict(timing, "unstable", fam.radius, None, found, reason=why)
    if fam.zoh is None:  # no derived gap bound: the grid points alone prove nothing
        return JitterVerdict(timing, "not proved (necessary condition holds)", fam.radius,
                             None, found, reason=fam.no_bound)
    proof = prove(fam)
    if proof is not None and proof.bound < 1.0:
        return JitterVerdict(timing, "proved", fam.radius, proof.bound, found, proof.delta,
                             margin=proof.gamma, mismatch=fam.zoh.mismatch)
    if proof is None:
        why = "no common quadratic Lyapunov function at the grid points"
    else:
        why = (f"the margin at the grid points (‖J_i‖_P ≤ {proof.gamma:.3f}) does not cover "
               f"the derived gap bound δ ≤ {proof.delta:.3g}")
    return JitterVerdict(timing, "not proved (necessary condition holds)", fam.radius,
                         None if proof is None else proof.bound, found,
                         None if proof is None else proof.delta, why,
                         None if proof is None else proof.gamma, fam.zoh.mismatch)


@dataclass(frozen=True)
class Budget:
    """The largest delay jitter proved, the constant-delay (necessary) boundary, the
    smallest jitter at which the adversarial search found a growing sequence, and the
    time the analysis took (s); why the smallest jitter tried above the proved one is not
    proved; the adversarial search's worst sequence inside the proved budget and the
    growing one it found at the smallest destabilising jitter (None: none found)."""

    proved: float
    necessary: float
    destabilising: float
    seconds: float
    reason: str = ""
    inside: Search | None = None
    growing: Search | None = None


def largest(ok: object, hi: float, rel_tol: float = 0.05) -> float:
    """The largest x in [0, hi] with ok(x), by bisection (ok monotone)."""
    assert callable(ok)
    if ok(hi):
        return hi
    lo = 0.0
    if not ok(lo):
        return 0.0
    while hi - lo > rel_tol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


def budget(s: LoopSetting, gain: float, search_only: bool = False) -> Budget:
    """The delay-jitter budget about the setting's delay D (latencies in [D − J, D + J], the
    period h): proved, necessary (every constant latency stable), and the smallest found
    destabilising, each searched up to the model's limit D + J < h (``search_only``: the
    last only)."""
    start = time.perf_counter()
    loop = loop_for(s)
    limit = 0.999 * s.h - s.delay
    necessary = 0.0 if search_only else min(limit, max(0.0, max_delay(s, gain) - s.delay))
    failed: dict[float, str] = {}  # jitter tried and not proved: why
    grew: dict[float, Search] = {}  # jitter at which the search found a growing sequence

    def proved(j: float) -> bool:
        v = verdict(loop, gain, delay_jitter(s.h, s.delay, j))
        if v.verdict != "proved":
            failed[j] = v.reason
        return v.verdict == "proved"

    def calm(j: float) -> bool:
        found = adversarial(loop, gain, delay_jitter(s.h, s.delay, j))
        if found.rate >= 1.0 + GROWTH_TOL:
            grew[j] = found
        return found.rate < 1.0 + GROWTH_TOL

    worst = largest(calm, limit)
    growing = grew[min(grew)] if grew else None
    if search_only:
        return Budget(0.0, 0.0, worst, time.perf_counter() - start, growing=growing)
    if necessary <= 0.0:
        failed[0.0] = "unstable at the setting (no constant latency in range is stable)"
    good = largest(proved, necessary) if necessary > 0.0 else 0.0
    inside = adversarial(loop, gain, delay_jitter(s.h, s.delay, good)) if good > 0 else None
    above = [j for j in failed if j >= good]
    return Budget(good, necessary, worst, time.perf_counter() - start,
                  failed[min(above)] if above else "", inside, growing)


def sequence_growth(loop: ClosedLoop, gain: float, sequence: tuple[tuple[float, float], ...],
                    repeats: int = 10, size: float = 1e-5) -> float:
    """The nonlinear closed loop on the model plant (the one-sample map itself, not its
    linearisation) run under ``sequence`` repeated: the growth per sample of the distance
    between the runs from the operating point and from a perturbed one, on the loop's
    wheel rates and law state (a growth ≥ 1 is a divergence)."""
    z0 = loop.points[0]
    rng = np.random.default_rng(46)
    z1 = z0.copy()
    eta = loop.sl["plant_eta"]
    z1[eta] += size * rng.standard_normal(eta.stop - eta.start)
    first = float(np.linalg.norm(z1 - z0))
    saved = loop.period, loop.lag, loop.frac
    a, b = loop.at_gain(z0, gain), loop.at_gain(z1, gain)
    n = 0
    try:
        for h, d in sequence * repeats:
            loop.period, loop.lag, loop.frac = h, 0, d / h
            k = loop.k + n
            a, b = loop.step(a, k, gain, loop.held_at[0]), loop.step(b, k, gain, loop.held_at[0])
            n += 1
    finally:
        loop.period, loop.lag, loop.frac = saved
    gap = float(np.linalg.norm((b - a)[eta]))
    return (max(gap, 1e-300) / first) ** (1.0 / n)


@dataclass(frozen=True)
class Replay:
    """A timing sequence replayed in the closed loop: the plant it ran on, the run, whether
    it diverged (:func:`runtime.stability.verification.diverged`) and its last third's
    largest ‖(e, ė)‖ over its middle third's (> 1: the error grows)."""

    plant: str
    run: closed_loop.Run
    diverged: bool
    growth: float


def replay(code: RobotCode, name: str, formulation: str, nominal: dict[str, float],
           exp: Experiment, sequence: tuple[tuple[float, float], ...],
           duration: float = 10.0) -> Replay:
    """``sequence`` of (period, latency), repeated from the first sample on, in the closed
    loop (:func:`runtime.sim.loop.run`, its timing :class:`runtime.sim.timing.GivenTiming`)
    on the plant ``[plant] model`` names: the model, or MuJoCo (the engine, not the
    linearisation the budget is proved on). The experiment as the analysis sees it
    (:func:`runtime.stability.verification.linear_experiment`: no friction, payload nor
    torque limit), on its circle of ``duration`` s."""
    lin = linear_experiment(exp)
    lin = replace(lin, paths=replace(lin.paths, circle_duration=duration))
    ref = paths.circle(code, nominal, lin)
    r = closed_loop.run(code, name, formulation, ref, nominal, lin,
                        plant=plant_for(code, lin, nominal), timing=GivenTiming(sequence))
    n = len(r.error_norm)
    middle = float(np.max(r.error_norm[n // 3: 2 * n // 3])) if n >= 3 else float("nan")
    last = float(np.max(r.error_norm[2 * n // 3:])) if n >= 3 else float("nan")
    return Replay(exp.plant.model, r, diverged(r), last / max(middle, 1e-300))
