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
for that γ. Between grid points, J(h, D) = J_i + Δ with ‖Δ‖_P ≤ δ = SAFETY Σ_axes L ·
(half a grid step), L the largest slope of J in the P-norm between neighbouring grid
points per grid step (an estimate: the bound is stated, not derived; SAFETY = 2 covers
a slope up to twice the largest seen between grid points), so ‖J‖_P ≤ γ + δ everywhere
in the range. The verdict: "proved" when γ + δ < 1,
"unstable" when some constant timing in the range has a spectral radius ≥ 1 (or a
switching sequence found by :func:`adversarial` grows), else "not proved (necessary
condition holds)".

Assumptions (stated with every verdict): the linearisation about the nominal steady
motion (a period that differs from the law's h also forces the loop: the reference's
time base; a bounded disturbance where the linear part is proved stable), the
experiment's plant, sensing and configuration, D_max < h_min.
"""

from __future__ import annotations

import itertools
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
from runtime.stability.sampled_loop import ClosedLoop, LoopSetting, loop_states, max_delay
from runtime.stability.verification import diverged, linear_experiment

Matrix = NDArray[np.float64]
GRID = (9, 5)  # points on the varying axis of a range that varies in one, per axis in two
SAFETY = 2.0  # the Lipschitz estimate's margin (stated in the verdict)
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
    """J on the grid of a timing range, reduced (see the module docstring)."""

    timing: Timing
    hs: tuple[float, ...]
    ds: tuple[float, ...]
    mats: tuple[Matrix, ...]  # row-major over (h, D)
    radius: float  # the largest constant-timing spectral radius on the grid
    # neighbouring grid points: (J_b − J_a, half the distance between them) per axis
    steps: tuple[tuple[tuple[Matrix, float], ...], ...]

    def delta(self, p: Matrix) -> float:
        """The gap bound between grid points in the P-norm: SAFETY times the largest slope
        of J between neighbours, times the half-step, summed over the axes."""
        root = np.real(sqrtm(p))
        inv = np.linalg.inv(root)
        return SAFETY * sum(max((float(np.linalg.norm(root @ d @ inv, 2)) * half
                                 for d, half in axis), default=0.0) for axis in self.steps)


def grid(lo: float, hi: float, n: int) -> tuple[float, ...]:
    return (lo,) if hi - lo < 1e-12 else tuple(float(x) for x in np.linspace(lo, hi, n))


def loop_for(s: LoopSetting, tail: int = 20) -> ClosedLoop:
    """The loop with one command in flight kept in its state (the latency can vary)."""
    return ClosedLoop(replace(s, in_flight=max(1, s.in_flight)), tail)


def reduce(mats: list[Matrix]) -> list[Matrix]:
    """The maps on the quotient by every mode all of them keep at 1: restricted to the
    kernel of their common left invariants, then modulo their common fixed vectors."""
    n = len(mats[0])
    left = null_space(np.vstack([(m - np.eye(n)).T for m in mats]), rcond=NEUTRAL)
    basis = null_space(left.T) if left.size else np.eye(n)
    mats = [basis.T @ m @ basis for m in mats]
    n = len(mats[0])
    fixed = null_space(np.vstack([m - np.eye(n) for m in mats]), rcond=NEUTRAL)
    if fixed.size:
        rest = null_space(fixed.T)
        mats = [rest.T @ m @ rest for m in mats]
    return mats


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
    mats = reduce([m[ix] for m in full])
    radius = max(float(np.abs(np.linalg.eigvals(m)).max()) for m in mats)
    at = np.array(mats).reshape(len(hs), len(ds), *mats[0].shape)
    along_h = tuple((at[i + 1, j] - at[i, j], 0.5) for i in range(len(hs) - 1)
                    for j in range(len(ds)))
    along_d = tuple((at[i, j + 1] - at[i, j], 0.5) for i in range(len(hs))
                    for j in range(len(ds) - 1))
    return Family(timing, hs, ds, tuple(mats), radius, (along_h, along_d))


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
    """What the SDP found: the decrease γ at the grid points, P's condition number κ, the
    gap bound δ (P-norm) and the bound on ‖J‖_P over the whole range, γ + δ."""

    gamma: float
    kappa: float
    delta: float  # in the P-norm

    @property
    def bound(self) -> float:
        return self.gamma + self.delta


def prove(fam: Family) -> Proof | None:
    """The best bound γ + δ over a few γ between the smallest feasible and 1."""
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
            proof = Proof(float(gamma), found[0], fam.delta(found[1]))
            if best is None or proof.bound < best.bound:
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
    """The verdict for one timing range, with what it rests on."""

    timing: Timing
    verdict: str  # "proved", "not proved (necessary condition holds)" or "unstable"
    radius: float  # the largest constant-timing spectral radius on the grid
    bound: float | None  # γ + δ, the bound on ‖J‖_P over the range (None: no common P)
    search: Search | None = None


def verdict(loop: ClosedLoop, gain: float, timing: Timing, search: bool = False
            ) -> JitterVerdict:
    fam = family(loop, gain, timing)
    found = adversarial(loop, gain, timing) if search else None
    if fam.radius >= 1.0 + GROWTH_TOL or (found is not None and found.rate >= 1.0 + GROWTH_TOL):
        return JitterVerdict(timing, "unstable", fam.radius, None, found)
    proof = prove(fam)
    if proof is not None and proof.bound < 1.0:
        return JitterVerdict(timing, "proved", fam.radius, proof.bound, found)
    return JitterVerdict(timing, "not proved (necessary condition holds)", fam.radius,
                         None if proof is None else proof.bound, found)


@dataclass(frozen=True)
class Budget:
    """The largest delay jitter proved, the constant-delay (necessary) boundary, the
    smallest jitter at which the adversarial search found a growing sequence, and the
    time the analysis took (s)."""

    proved: float
    necessary: float
    destabilising: float
    seconds: float


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

    def proved(j: float) -> bool:
        return verdict(loop, gain, delay_jitter(s.h, s.delay, j)).verdict == "proved"

    def calm(j: float) -> bool:
        return adversarial(loop, gain, delay_jitter(s.h, s.delay, j)).rate < 1.0 + GROWTH_TOL

    if search_only:
        return Budget(0.0, 0.0, largest(calm, limit), time.perf_counter() - start)
    return Budget(largest(proved, necessary), necessary, largest(calm, limit),
                  time.perf_counter() - start)


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
