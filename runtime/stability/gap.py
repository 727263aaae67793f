"""A derived bound on the timed loop map J(h, D) between the grid points of a timing range
(the jitter budget of :mod:`runtime.stability.jitter`).

Structure. Over one sample of plant period h whose command is D late (0 ≤ D < h, one
command in flight), the plant is under zero-order hold: the command in flight τ_old over
[0, D], the new one τ_k = K z_k over [D, h]. Linearised about the loop's steady motion (a
relative equilibrium: in the plant's loop states — wheel angles, hitch angles, wheel rates,
never the pose — its continuous linearisation ẋ = A x + B τ is constant along the sample),
the plant's rows of J are

    X(h, D) = e^{Ah} S_x + (Γ(h) − Γ(h − D)) S_old + Γ(h − D) K,   Γ(t) = ∫₀ᵗ e^{As} ds B,

with S_x, S_old the selections of the plant's state and of the command in flight from the
loop state z, and K the law's Jacobian (J's row of the new command). Every other row of J
— the law's, the odometry's, the command stored — does not depend on (h, D): the law keeps
its configured h whatever the plant's period (a TDE law's division by h is by that h), and
the sensing reads the plant at the sample instant. Both are checked on the grid (below).

Derivatives (A e^{Ah} = e^{Ah} A):

    ∂X/∂h = e^{Ah} R₁ + e^{A(h−D)} R₂,   ∂X/∂D = −e^{A(h−D)} R₂,
    R₁ = A S_x + B S_old,   R₂ = B (K − S_old).

So for (h, D) in the cell of a grid point (h_i, D_j) (|h − h_i| ≤ Δh/2, |D − D_j| ≤ ΔD/2:
every point of the range is in the cell of its nearest grid point), along the segment
between them (the mean-value inequality, h ∈ H, h − D ∈ S on it),

    ‖J(h, D) − J(h_i, D_j)‖ ≤ L_h |h − h_i| + L_D |D − D_j|,
    L_h = sup_{s∈H} ‖e^{As} R₁‖ + sup_{s∈S} ‖e^{As} R₂‖,   L_D = sup_{s∈S} ‖e^{As} R₂‖,

and, with a = ‖A‖, b = ‖B‖, k = ‖K‖ and E = e^{a h_max} (‖e^{As}‖ ≤ e^{a s}), the closed form
L_h ≤ E (a + b (k + 2)), L_D ≤ E b (k + 1) (:func:`closed_form`). The computed bound is the
tighter sup: ‖L e^{As} R‖ at points s_j σ apart, plus ‖L e^{A s_j}‖ (e^{aσ/2} − 1) ‖R‖, since
e^{As} = e^{A s_j} e^{A(s − s_j)} and ‖e^{Aε} − I‖ ≤ e^{a|ε|} − 1. In the P-norm of the
Lyapunov certificate (the reduced coordinates W of :func:`runtime.stability.jitter.reduce`:
J_red = Wᵀ J W) L = P^½ Wᵀ E_p (E_p: the plant's rows) on the left and W P^-½ on the right
of R₁, R₂; the certificate's decrease ‖J_i‖_P at the grid point then covers the cell when
‖J_i‖_P + δ_i < 1, δ_i = the bound above in the P-norm at the cell's half steps.

Checked, or the bound is not derived (and the verdict is not "proved", with the reason):
the plant's loop states receive nothing from its other states in A (the pose does not act
on the dynamics); every row but the plant's is the same at every grid point (within
:data:`ROW_TOL`); the plant's rows computed (central differences of the sampled map, RK4)
equal X(h_i, D_j) of A, B (central differences of the generated plant's state derivative at
the operating point) within :data:`MODEL_TOL` — the mismatch m is stated and 2m added to δ
(at the grid point and, assumed no larger, inside the cell); the modes the reduction
removes are neutral at every timing, not only on the grid (:func:`check_reduction`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm, sqrtm

from runtime.stability.sampled_loop import ClosedLoop

Matrix = NDArray[np.float64]
ROW_TOL = 1e-6  # relative: the rows that must not depend on the timing
MODEL_TOL = 1e-3  # relative: the computed plant rows against the ZOH model of A, B
COUPLING_TOL = 1e-8  # relative: the plant's other states acting on its loop states
NEUTRAL_TOL = 1e-6  # relative: a removed mode that stays neutral off the grid
S_POINTS = 400  # points of the s-grid over [0, h_max] for the sups


class NoGapBound(ValueError):
    """The loop's structure does not allow the derived gap bound (the sentence says why)."""


@dataclass(frozen=True)
class ZohRows:
    """The ZOH structure of the plant's rows of J (see the module docstring), on the loop
    states (positions in them): the plant's states, the command in flight, A and B on the
    plant's loop states, the law's Jacobian K, and the mismatch m of the computed rows."""

    plant: tuple[int, ...]
    old: tuple[int, ...]  # -1: that wheel's command in flight is not a loop state
    a: Matrix
    b: Matrix
    k: Matrix
    mismatch: float

    @property
    def n(self) -> int:
        return self.k.shape[1]

    def selection(self, rows: tuple[int, ...]) -> Matrix:
        out = np.zeros((len(rows), self.n))
        out[np.arange(len(rows)), list(rows)] = 1.0
        return out

    @property
    def s_old(self) -> Matrix:
        """S_old (a zero row where the command in flight is not a loop state)."""
        out = np.zeros((len(self.old), self.n))
        for r, c in enumerate(self.old):
            if c >= 0:
                out[r, c] = 1.0
        return out

    @property
    def r1(self) -> Matrix:
        return self.a @ self.selection(self.plant) + self.b @ self.s_old

    @property
    def r2(self) -> Matrix:
        return self.b @ (self.k - self.s_old)

    def rows_at(self, h: float, d: float) -> Matrix:
        """X(h, D): the plant's rows of J by the ZOH model."""
        phi_h, gam_h = flow(self.a, self.b, h)
        _, gam_s = flow(self.a, self.b, h - d)
        return (phi_h @ self.selection(self.plant) + (gam_h - gam_s) @ self.s_old
                + gam_s @ self.k)


def flow(a: Matrix, b: Matrix, t: float) -> tuple[Matrix, Matrix]:
    """(e^{At}, Γ(t) = ∫₀ᵗ e^{As} ds B) by one exponential of the augmented matrix."""
    n, m = b.shape
    aug = np.zeros((n + m, n + m))
    aug[:n, :n], aug[:n, n:] = a, b
    e = expm(aug * t)
    return e[:n, :n], e[:n, n:]


def continuous(loop: ClosedLoop) -> tuple[Matrix, Matrix]:
    """(∂f/∂x, ∂f/∂τ) of the generated plant's state derivative x' = f(x, τ), x = (q, η),
    at the operating point (the plant's state at sample k, the command it runs under), by
    central differences; no friction, as the loop's map."""
    code, lib = loop.code, loop.lib
    nq, nu = code.nq, code.nu
    sl, z0, z1 = loop.sl, loop.points[0], loop.points[1]
    x0 = np.concatenate([z0[sl["plant_q"]], z0[sl["plant_eta"]]])
    tau0 = z1[sl["in_flight0"]]  # the command computed at sample k (the steady one)
    ffi, fn = lib.ffi, getattr(lib.lib, f"{code.prefix}_plant_state_derivative")
    real = f"{code.prefix}_real_t"
    xb, tb, out = ffi.new(f"{real}[{nq + nu}]"), ffi.new(f"{real}[{nu}]"), ffi.new(
        f"{real}[{nq + nu}]")

    def f(x: NDArray[np.float64], tau: NDArray[np.float64]) -> NDArray[np.float64]:
        xb[0:nq + nu] = [float(v) for v in x]
        tb[0:nu] = [float(v) for v in tau]
        fn(loop.pp, xb, tb, out)
        return np.array([out[i] for i in range(nq + nu)])

    def jac(g: object, v0: NDArray[np.float64]) -> Matrix:
        assert callable(g)
        cols = []
        for c in range(len(v0)):
            d = 1e-6 * max(1.0, abs(v0[c]))
            vp, vm = v0.copy(), v0.copy()
            vp[c] += d
            vm[c] -= d
            cols.append((g(vp) - g(vm)) / (2 * d))
        return np.array(cols).T

    return jac(lambda x: f(x, tau0), x0), jac(lambda t: f(x0, t), tau0)


def zoh_rows(loop: ClosedLoop, states: list[int], hs: tuple[float, ...],
             ds: tuple[float, ...], whole: list[Matrix]) -> ZohRows:
    """The ZOH structure of the timed Jacobians ``whole`` (row-major over (h, D)) on the
    loop ``states``, every check of the module docstring made; :class:`NoGapBound` says
    which fails."""
    full = [m[np.ix_(states, states)] for m in whole]
    sl, nq = loop.sl, loop.code.nq
    pos = {s: i for i, s in enumerate(states)}
    plant_x = [i for i in range(sl["plant_q"].start, sl["plant_eta"].stop) if i in pos]
    plant = tuple(pos[i] for i in plant_x)
    flight = range(sl["in_flight0"].start, sl["in_flight0"].stop)
    # a command in flight that no loop state reads (no latency: G_old = 0; or its column
    # below the loop states' threshold) is left out as the loop states leave it: -1
    old = tuple(pos.get(i, -1) for i in flight)
    scale = max(1.0, max(float(np.abs(m).max()) for m in full))
    others = [i for i in range(len(states)) if i not in set(plant)]
    moved = max(float(np.abs(m[others] - full[0][others]).max(initial=0.0)) for m in full)
    if moved > ROW_TOL * scale:
        raise NoGapBound(f"rows other than the plant's change with the timing (by {moved:.2g}: "
                         "a sensing window read inside the period?), which the ZOH bound "
                         "does not cover")
    a_full, b_full = continuous(loop)
    xs = [i - sl["plant_q"].start for i in plant_x]  # x = (q, η) indices
    rest = [i for i in range(nq + loop.code.nu) if i not in set(xs)]
    ascale = max(1.0, float(np.abs(a_full).max()))
    coupling = float(np.abs(a_full[np.ix_(xs, rest)]).max()) if rest else 0.0
    if coupling > COUPLING_TOL * ascale:
        raise NoGapBound(f"the plant's other states act on its loop states (by {coupling:.2g}),"
                         " so its rows are not the flow of its loop states alone")
    a, b = a_full[np.ix_(xs, xs)], b_full[xs]
    # K: the new command's rows (kept in the full map even where no loop state reads it)
    z = ZohRows(plant, old, a, b, whole[0][np.ix_(list(flight), states)], 0.0)
    mismatch = 0.0
    for (h, d), m in zip([(h, d) for h in hs for d in ds], full, strict=True):
        mismatch = max(mismatch, float(np.linalg.norm(m[list(plant)] - z.rows_at(h, d), 2)))
    if mismatch > MODEL_TOL * scale:
        raise NoGapBound(f"the computed plant rows differ from the ZOH flow of the plant's "
                         f"continuous linearisation by {mismatch:.2g} (not a steady motion "
                         "the sample's flow keeps?)")
    return ZohRows(plant, old, a, b, z.k, mismatch)


def check_reduction(z: ZohRows, left: Matrix, inner: Matrix, fixed: Matrix, vary_h: bool
                    ) -> None:
    """:class:`NoGapBound` unless the modes the reduction removes are neutral at every
    timing of the range, not only on the grid: J(h, D) − J(h_i, D_j) = E_p ∫ ∂X, and ∂X is
    e^{As} R with R = R₂ (and R₁ where h varies), so it suffices that the common left
    invariants w (columns of ``left``) have w_pᵀ A^k R = 0 and the fixed vectors v
    (``fixed``, found in the coordinates ``inner`` after the first step) have
    innerᵀ E_p A^k R v = 0 for k < dim A (then for every e^{As}, by Cayley–Hamilton)."""
    rs = [z.r2, z.r1] if vary_h else [z.r2]
    an = max(1.0, float(np.linalg.norm(z.a, 2)))
    worst = 0.0
    ip = inner[list(z.plant)]
    for r in rs:
        m = r.copy()
        scale = max(1.0, float(np.abs(r).max()))
        for _ in range(len(z.a)):
            if left.size:
                worst = max(worst, float(np.abs(left[list(z.plant)].T @ m).max()) / scale)
            if fixed.size:
                worst = max(worst, float(np.abs(ip.T @ m @ fixed).max()) / scale)
            m = z.a @ m / an
    if worst > NEUTRAL_TOL:
        raise NoGapBound(f"a mode neutral on the grid is not neutral between its points "
                         f"(by {worst:.2g}), so the reduced family does not cover the range")


def sup_norm(a: Matrix, left: Matrix, right: Matrix, lo: float, hi: float, h_max: float
             ) -> float:
    """A bound on sup_{s ∈ [lo, hi]} ‖left e^{As} right‖ (module docstring)."""
    sigma = h_max / S_POINTS
    j0, j1 = math.floor(lo / sigma), math.ceil(hi / sigma)
    grow = math.expm1(float(np.linalg.norm(a, 2)) * sigma / 2)
    rn = float(np.linalg.norm(right, 2))
    step = expm(a * sigma)
    e = expm(a * (j0 * sigma))
    best = 0.0
    for _ in range(j0, j1 + 1):
        le = left @ e
        best = max(best, float(np.linalg.norm(le @ right, 2))
                   + float(np.linalg.norm(le, 2)) * grow * rn)
        e = step @ e
    return best


@dataclass(frozen=True)
class Cells:
    """The cells of a grid: per grid point (row-major over (h, D)), the h-range and the
    (h − D)-range along the segments from it, and the half steps."""

    h_lo: tuple[float, ...]
    h_hi: tuple[float, ...]
    s_lo: tuple[float, ...]
    s_hi: tuple[float, ...]
    half_h: float
    half_d: float
    h_max: float


def cells(hs: tuple[float, ...], ds: tuple[float, ...]) -> Cells:
    half_h = 0.5 * (hs[1] - hs[0]) if len(hs) > 1 else 0.0
    half_d = 0.5 * (ds[1] - ds[0]) if len(ds) > 1 else 0.0
    h_lo, h_hi, s_lo, s_hi = [], [], [], []
    for h in hs:
        for d in ds:
            hl, hh = max(hs[0], h - half_h), min(hs[-1], h + half_h)
            dl, dh = max(ds[0], d - half_d), min(ds[-1], d + half_d)
            h_lo.append(hl)
            h_hi.append(hh)
            s_lo.append(hl - dh)
            s_hi.append(hh - dl)
    return Cells(tuple(h_lo), tuple(h_hi), tuple(s_lo), tuple(s_hi), half_h, half_d, hs[-1])


def gap_bounds(z: ZohRows, basis: Matrix, p: Matrix, c: Cells) -> list[float]:
    """δ_i per grid point: the bound on ‖J_red(h, D) − J_red(h_i, D_j)‖_P over its cell
    (with ``p`` the identity, the Euclidean norm), the model mismatch's allowance 2m
    included."""
    root = np.real(sqrtm(p))
    inv = np.linalg.inv(root)
    ep = np.zeros((z.n, len(z.plant)))
    ep[list(z.plant), np.arange(len(z.plant))] = 1.0
    left = root @ basis.T @ ep
    right = basis @ inv
    r1, r2 = z.r1 @ right, z.r2 @ right
    # a single timing has no cell: the computed J is the map itself there
    allowance = 2.0 * z.mismatch * float(np.linalg.norm(left, 2)) * float(
        np.linalg.norm(right, 2)) if c.half_h or c.half_d else 0.0
    out = []
    for i in range(len(c.h_lo)):
        on_s = sup_norm(z.a, left, r2, c.s_lo[i], c.s_hi[i], c.h_max)
        on_h = sup_norm(z.a, left, r1, c.h_lo[i], c.h_hi[i], c.h_max) if c.half_h else 0.0
        out.append(c.half_h * (on_h + on_s) + c.half_d * on_s + allowance)
    return out


def closed_form(z: ZohRows, h_max: float) -> tuple[float, float]:
    """(L_h, L_D) by the closed form E (a + b (k + 2)), E b (k + 1), E = e^{a h_max}: a
    bound on the computed sups' Lipschitz constants (Euclidean, before the reduction)."""
    a, b = float(np.linalg.norm(z.a, 2)), float(np.linalg.norm(z.b, 2))
    k = float(np.linalg.norm(z.k, 2))
    e = math.exp(a * h_max)
    return e * (a + b * (k + 2)), e * b * (k + 1)
