"""ROC's bounds (α, φ) over a box of physical quantities, by a sound enclosure.

ROC's gain needs α ≥ ‖M⁻¹ M̂ − I‖₂ and φ ≥ ‖M⁻¹ (H − Ĥ)‖ over the robots it may meet
(Roy et al. 2017, (22)–(24); docs/PAPER.md item 11). For a bodies-and-wheels robot the
robots are stated as a box P of physical quantities p (masses, yaw inertias, centres of
mass, a payload: ``runtime.experiment.physical``), which reach the model through the
generated map β(p) (``plant_params_from_physical``, ``modeling.physical_map``).

Why not the vertices of P: M̄(q; β) = Sᵀ M S is affine in β (S depends on the kinematics
only; checked here on the generated code), and β(p) is affine in each mass and inertia but
quadratic in a centre-of-mass coordinate (m c²), so the image of P is not the hull of its
vertices' images when a centre of mass moves; and α(p) = ‖M(p)⁻¹ M̂ − I‖₂ is not convex in
β, so even over a polytope its maximum need not sit at a vertex. What is computed instead,
for each sampled configuration q (the lumped method's :func:`configurations`) and sampled
wheel rates η (:func:`rate_samples`), is an upper bound over all of P:

* on a sub-box B with centre c, each β_j(B) ⊂ [β_j(c) − ρ_j, β_j(c) + ρ_j] by interval
  arithmetic on β's polynomial terms (robot.py's ``PHYSICAL_TERMS``, exact per term);
* with M_c = M̄(q; β(c)), G_j = ∂M̄/∂β_j, E = Σ (β_j − β_j(c)) G_j and
  s = Σ ρ_j ‖M_c⁻¹ G_j‖ < 1, M(p)⁻¹ = (I + M_c⁻¹ E)⁻¹ M_c⁻¹ and
  X(p) − X_c = −(I + M_c⁻¹ E)⁻¹ M_c⁻¹ E (X_c + I) for X = M⁻¹ M̂ − I, so

      α(p) ≤ ‖X_c‖ + Σ ρ_j ‖M_c⁻¹ G_j (X_c + I)‖ / (1 − s)
      φ(p, η) ≤ (‖M_c⁻¹ (H(β(c)) − Ĥ)‖ + Σ ρ_j ‖M_c⁻¹ H_j(η)‖) / (1 − s)

  (H̄ is affine in β too, H_j = ∂H̄/∂β_j at q, η);
* the box is bisected (branch and bound: the sub-box of the largest α bound, along the
  quantity whose range contributes most) until the largest bound is within
  :data:`ALPHA_TOL` of the largest α evaluated at a centre, or :data:`MAX_BOXES` sub-boxes.

The result is an over-approximation over P (the gap to the largest evaluated robot is
reported), sound over P at each sampled (q, η); configurations and wheel rates are sampled
as in the lumped method (``runtime.bindings.uncertainty``), not enclosed.
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from runtime.bindings.generated import RobotCode
from runtime.bindings.uncertainty import checked, configurations
from runtime.experiment.physical import PhysicalUncertainty, physical_box

Array = NDArray[np.float64]
ALPHA_TOL = 0.01  # stop refining once the bound is this close to an evaluated robot's α
MAX_BOXES = 200  # sub-boxes per configuration at most
MAX_VERTEX_DIMS = 12  # the box's corners are evaluated (a lower bound) up to this many
RATE_SAMPLES = 8  # wheel-rate vectors per configuration for φ (fixed seed)
ROUNDING = 1e-9  # relative outward rounding of the enclosures (floating point)


@dataclass(frozen=True)
class PhysicalModel:
    """A robot's map from physical quantities to its model's parameters, from its generated
    code: ``keys`` (the inputs, in order), ``nominal`` (the robot file's values), the
    outputs' keys and polynomial terms."""

    code: RobotCode
    keys: tuple[str, ...]
    nominal: tuple[float, ...]
    outputs: tuple[str, ...]
    terms: tuple[tuple[tuple[float, tuple[tuple[int, int], ...]], ...], ...]

    def params(self, phys: Array) -> dict[str, float]:
        """The plant parameters of the robot with physical quantities ``phys`` (the
        generated ``plant_params_from_physical``; radii the robot's own)."""
        beta = self.code.plant.plant_params_from_physical(np.asarray(phys, dtype=np.float64))
        out = dict(self.code.plant_defaults)
        out.update(zip(self.outputs, (float(b) for b in np.ravel(beta)), strict=True))
        return out

    def beta(self, phys: Array) -> Array:
        """The outputs of the map for a batch of physical vectors (rows), from the terms
        (vectorised; the generated function evaluates one robot)."""
        phys = np.atleast_2d(phys)
        out = np.zeros((phys.shape[0], len(self.outputs)))
        for j, terms in enumerate(self.terms):
            for coeff, powers in terms:
                value = np.full(phys.shape[0], coeff)
                for i, e in powers:
                    value = value * phys[:, i] ** e
                out[:, j] += value
        return out

    def enclose(self, lo: Array, hi: Array) -> tuple[Array, Array]:
        """[min, max] of each output over the box [lo, hi] by interval arithmetic on its
        terms (each term's range is exact; their sum encloses the output's)."""
        return enclose_terms(self.terms, lo, hi)

    def derivative_terms(self, k: int) -> tuple[Terms, ...]:
        """The terms of ∂β_j/∂p_k for every output j."""
        out = []
        for terms in self.terms:
            d = []
            for coeff, powers in terms:
                e = dict(powers).get(k, 0)
                if e:
                    rest = tuple((i, p) if i != k else (i, p - 1) for i, p in powers)
                    d.append((coeff * e, tuple((i, p) for i, p in rest if p)))
            out.append(tuple(d))
        return tuple(out)


Terms = tuple[tuple[float, tuple[tuple[int, int], ...]], ...]


def evaluate_terms(all_terms: tuple[Terms, ...], x: Array) -> Array:
    """Each polynomial at the point x."""
    out = np.zeros(len(all_terms))
    for j, terms in enumerate(all_terms):
        for coeff, powers in terms:
            v = coeff
            for i, e in powers:
                v *= x[i] ** e
            out[j] += v
    return out


def enclose_terms(all_terms: tuple[Terms, ...], lo: Array, hi: Array) -> tuple[Array, Array]:
    """[min, max] of each polynomial over the box [lo, hi] (interval arithmetic, each
    term exact, padded outward by :data:`ROUNDING`)."""
    blo = np.zeros(len(all_terms))
    bhi = np.zeros(len(all_terms))
    for j, terms in enumerate(all_terms):
        for coeff, powers in terms:
            a, b = coeff, coeff
            for i, e in powers:
                x0, x1 = lo[i] ** e, hi[i] ** e
                if e % 2 == 0 and lo[i] < 0 < hi[i]:
                    x0, x1 = 0.0, max(x0, x1)
                cands = (a * x0, a * x1, b * x0, b * x1)
                a, b = min(cands), max(cands)
            blo[j] += a
            bhi[j] += b
    pad = ROUNDING * (np.abs(blo) + np.abs(bhi)) + 1e-300
    return blo - pad, bhi + pad


def physical_model(code: RobotCode) -> PhysicalModel:
    """The map of a bodies-and-wheels robot's generated code; ``ValueError`` for a
    ``[lumped]`` robot or code generated before the map."""
    phys = getattr(code.robot, "PHYSICAL", None)
    terms = getattr(code.robot, "PHYSICAL_TERMS", None)
    if phys is None or terms is None or not hasattr(code.plant, "plant_params_from_physical"):
        raise ValueError(f"robot '{code.name}' has no map from physical quantities (a "
                         "[lumped] robot, or code generated before it: regenerate with "
                         "`wmr model`)")
    return PhysicalModel(code, tuple(phys), tuple(float(v[0]) for v in phys.values()),
                         tuple(terms), tuple(tuple(t) for t in terms.values()))


def box_of(code: RobotCode, decl: PhysicalUncertainty) -> dict[str, tuple[float, float]]:
    """The declaration resolved on the robot (``runtime.experiment.physical.physical_box``)."""
    layout = getattr(code.robot, "LAYOUT", None) or {"bodies": [], "wheels": []}
    return physical_box(decl, getattr(code.robot, "PHYSICAL", None),
                        tuple(b[0] for b in layout["bodies"]),
                        tuple(w[0] for w in layout["wheels"]), code.name)


def rate_samples(code: RobotCode, max_rate: float) -> list[Array]:
    """The wheel-rate vectors φ is bounded at, one list per configuration (fixed seed)."""
    rng = np.random.default_rng(7)
    return [rng.uniform(-max_rate, max_rate, size=(RATE_SAMPLES, code.nu))
            for _ in configurations(code)]


def _directions(code: RobotCode, keys: tuple[str, ...], p0: Mapping[str, float], q: Array,
                etas: Array) -> tuple[Array, Array, Array, Array]:
    """M̄(q; β0), G_j = ∂M̄/∂β_j, H̄(q, η; β0) and H_j per η, by differences (exact for an
    affine dependence, which is checked at a random combination)."""
    model = code.model

    def mh(p: Mapping[str, float]) -> tuple[Array, Array]:
        m = np.asarray(model.minimal_mass_matrix(q, dict(p)), dtype=np.float64)
        h = np.array([np.asarray(model.minimal_bias_forces(q, e, dict(p)), dtype=np.float64)
                      for e in etas])
        return m, h

    m0, h0 = mh(p0)
    g, hj = [], []
    for k in keys:
        step = max(1.0, abs(p0[k]))
        m1, h1 = mh({**p0, k: p0[k] + step})
        g.append((m1 - m0) / step)
        hj.append((h1 - h0) / step)
    rng = np.random.default_rng(13)
    w = rng.uniform(-1.0, 1.0, len(keys))
    trial = {**p0, **{k: p0[k] + wk * max(1.0, abs(p0[k])) for k, wk in zip(keys, w,
                                                                            strict=True)}}
    mt, ht = mh(trial)
    scale = max(1.0, *(abs(p0[k]) for k in keys))
    pred_m = m0 + np.tensordot(w * [max(1.0, abs(p0[k])) for k in keys], np.array(g), 1)
    pred_h = h0 + np.tensordot(w * [max(1.0, abs(p0[k])) for k in keys], np.array(hj), 1)
    if (np.max(np.abs(mt - pred_m)) > 1e-9 * scale * (1 + np.max(np.abs(mt)))
            or np.max(np.abs(ht - pred_h)) > 1e-9 * scale * (1 + np.max(np.abs(ht)))):
        raise ValueError(f"robot '{code.name}': its minimal M and H are not affine in "
                         f"{', '.join(keys)}; the physical bounds assume they are")
    return m0, np.array(g), h0, np.array(hj)


@dataclass(frozen=True)
class PhysicalBounds:
    """ROC's (α, φ) over a physical box: ``alpha``/``phi`` the sound upper bounds,
    ``alpha_seen`` the largest α of a robot evaluated in the box (the gap is the
    over-approximation), ``worst`` that robot's physical quantities, ``boxes`` the
    sub-boxes used, ``alphas`` the bound per configuration."""

    alpha: float
    phi: float
    alpha_seen: float
    worst: dict[str, float]
    boxes: int
    alphas: tuple[float, ...]


def _bounds_at(pm: PhysicalModel, lo: Array, hi: Array, nominal: Mapping[str, float],
               q: Array, etas: Array, formulation: str) -> tuple[float, float, float, Array,
                                                                 int]:
    """(α bound, φ bound, largest α seen, where, sub-boxes) at one configuration."""
    if formulation != "minimal":
        raise ValueError("physical bounds are computed in the minimal formulation (the one "
                         "a bodies-and-wheels robot has)")
    keys = pm.outputs
    p0 = {**pm.code.plant_defaults, **dict(nominal)}
    m0, g, h0, hj = _directions(pm.code, keys, p0, q, etas)
    beta0 = np.array([p0[k] for k in keys])
    m_hat = m0 + np.tensordot(np.array([nominal[k] for k in keys]) - beta0, g, 1)
    h_hat = h0 + np.tensordot(np.array([nominal[k] for k in keys]) - beta0, hj, 1)
    eye = np.eye(len(m0))
    free = [i for i in range(len(lo)) if hi[i] > lo[i]]

    dterms = {k: pm.derivative_terms(k) for k in free}

    def evaluate(blo: Array, bhi: Array) -> tuple[float, float, float, Array, Array]:
        # β(p) − β(c) = Σ_k (p_k − c_k) ∂_k β(ξ), ∂_k β_j(ξ) ∈ J_jk(c) ± r_jk over the box: E
        # is a sum over the varying quantities of (p_k − c_k)(D_k + Σ_j e_jk G_j),
        # D_k = Σ_j J_jk G_j, |e_jk| ≤ r_jk (coherent directions: one mass moves every β
        # it enters together).
        c = 0.5 * (blo + bhi)
        w = 0.5 * (bhi - blo)
        bc = pm.beta(c)[0]
        mc = m0 + np.tensordot(bc - beta0, g, 1)
        hc = h0 + np.tensordot(bc - beta0, hj, 1)
        inv = np.linalg.inv(mc)
        xc = inv @ m_hat - eye
        seen = float(np.linalg.norm(xc, 2))
        ig = np.einsum("ab,jbc->jac", inv, g)  # M_c⁻¹ G_j
        ig_norm = np.array([np.linalg.norm(x, 2) for x in ig])
        igx = np.array([np.linalg.norm(x @ (xc + eye), 2) for x in ig])
        ih = np.einsum("ab,jeb->jea", inv, hj)  # M_c⁻¹ H_j(η) per η
        ih_norm = np.linalg.norm(ih, axis=2)  # (outputs, etas)
        s_k, t_k, f_k = np.zeros(len(lo)), np.zeros(len(lo)), np.zeros((len(lo), len(etas)))
        for k in free:
            jc = evaluate_terms(dterms[k], c)
            dlo, dhi = enclose_terms(dterms[k], blo, bhi)
            r = np.maximum(np.maximum(dhi - jc, jc - dlo), 0.0)
            idk = np.tensordot(jc, ig, 1)
            s_k[k] = w[k] * (np.linalg.norm(idk, 2) + r @ ig_norm)
            t_k[k] = w[k] * (np.linalg.norm(idk @ (xc + eye), 2) + r @ igx)
            f_k[k] = w[k] * (np.linalg.norm(np.tensordot(jc, ih, 1), axis=1) + r @ ih_norm)
        s = float(s_k.sum())
        if s >= 1.0:
            return math.inf, math.inf, seen, c, s_k
        alpha = (seen + float(t_k.sum()) / (1.0 - s)) * (1 + ROUNDING)
        dh = np.linalg.norm((inv @ (hc - h_hat).T).T, axis=1)
        phi = float(np.max(dh + f_k.sum(axis=0))) / (1.0 - s) * (1 + ROUNDING)
        return alpha, phi, seen, c, t_k + s_k

    def split_dim(blo: Array, bhi: Array, score: Array) -> int:
        # the quantity whose range contributes most to the bound
        return max(free, key=lambda i: score[i])

    alpha, phi, seen, c, sens = evaluate(lo, hi)
    heap = [(-alpha, 0, lo, hi, phi, sens)]
    best_seen, where = seen, c
    if 0 < len(free) <= MAX_VERTEX_DIMS:  # the box's corners: robots that exist
        corners = np.array(list(itertools.product((0, 1), repeat=len(free))))
        pts = np.tile(lo, (len(corners), 1))
        pts[:, free] = np.where(corners == 1, hi[free], lo[free])
        mats = m0 + np.tensordot(pm.beta(pts) - beta0, g, 1)
        dev = np.linalg.solve(mats, np.broadcast_to(m_hat, mats.shape)) - eye
        alphas = np.linalg.norm(dev, 2, axis=(1, 2))
        if float(alphas.max()) > best_seen:
            best_seen, where = float(alphas.max()), pts[int(np.argmax(alphas))]
    count, n = 1, 1
    done_alpha, done_phi = 0.0, 0.0  # bounds of the boxes no longer refined
    while heap:
        neg, _, blo, bhi, _, bsens = heap[0]
        if -neg <= best_seen + ALPHA_TOL or count >= MAX_BOXES or not free:
            break
        heapq.heappop(heap)
        i = split_dim(blo, bhi, bsens)
        mid = 0.5 * (blo[i] + bhi[i])
        for a, b in ((blo[i], mid), (mid, bhi[i])):
            clo, chi = blo.copy(), bhi.copy()
            clo[i], chi[i] = a, b
            al, ph, se, cc, ss = evaluate(clo, chi)
            count += 1
            if se > best_seen:
                best_seen, where = se, cc
            heapq.heappush(heap, (-al, n, clo, chi, ph, ss))
            n += 1
    alpha_ub = max([done_alpha, *(-h[0] for h in heap)])
    phi_ub = max([done_phi, *(h[4] for h in heap)])
    return alpha_ub, phi_ub, best_seen, where, count


def physical_roc_bounds(code: RobotCode, nominal: Mapping[str, float],
                        box: Mapping[str, tuple[float, float]], formulation: str,
                        max_rate: float) -> PhysicalBounds:
    """(α, φ) of ROC over the physical ``box`` (key -> (min, max), every input of the map),
    as the module docstring says; no check of α."""
    items = tuple((k, tuple(map(float, box[k]))) for k in physical_model(code).keys)
    return _physical_roc_bounds(code, tuple(nominal.items()), items, formulation,
                                float(max_rate))


@lru_cache(maxsize=32)
def _physical_roc_bounds(code: RobotCode, nominal_items: tuple[tuple[str, float], ...],
                         box: tuple[tuple[str, tuple[float, ...]], ...], formulation: str,
                         max_rate: float) -> PhysicalBounds:
    pm = physical_model(code)
    nominal = checked(code, dict(nominal_items), "nominal")
    lo = np.array([b[1][0] for b in box])
    hi = np.array([b[1][1] for b in box])
    alphas, phis, seen, worst, boxes = [], [], -1.0, lo, 0
    for q, etas in zip(configurations(code), rate_samples(code, max_rate), strict=True):
        a, f, s, w, n = _bounds_at(pm, lo, hi, nominal, q, etas, formulation)
        alphas.append(a)
        phis.append(f)
        boxes += n
        if s > seen:
            seen, worst = s, w
    return PhysicalBounds(max(alphas), max(phis), seen,
                          dict(zip(pm.keys, map(float, worst), strict=True)), boxes,
                          tuple(alphas))


def check_physical_roc(code: RobotCode, nominal: Mapping[str, float],
                       decl: PhysicalUncertainty, formulation: str,
                       max_rate: float) -> tuple[float, float]:
    """ROC's (α, φ) over the declared physical box; ``ValueError`` if α < 1 cannot be
    shown, naming the physical range that breaks it: the quantity whose range alone
    (every other quantity nominal) gives the largest α bound."""
    box = box_of(code, decl)
    b = physical_roc_bounds(code, nominal, box, formulation, max_rate)
    if b.alpha < 1.0:
        return b.alpha, b.phi
    pm = physical_model(code)
    nominal_box = {k: (v, v) for k, v in zip(pm.keys, pm.nominal, strict=True)}
    single = []
    for k, (lo, hi) in box.items():
        if hi > lo:
            one = physical_roc_bounds(code, nominal, {**nominal_box, k: (lo, hi)},
                                      formulation, max_rate)
            single.append((one.alpha, k, lo, hi))
    worst = max(single) if single else (b.alpha, "?", 0.0, 0.0)
    real = (f"a robot of the box reaches alpha = {b.alpha_seen:.3f}" if b.alpha_seen >= 1
            else f"the largest alpha found at a robot of the box is {b.alpha_seen:.3f}")
    raise ValueError(
        f"ROC needs alpha < 1 over the physical uncertainty ({decl.describe()}): its bound "
        f"is {b.alpha:.3f} ({real}); {worst[1]} over [{worst[2]:g}, {worst[3]:g}] alone "
        f"gives alpha up to {worst[0]:.3f}: narrow that range")
