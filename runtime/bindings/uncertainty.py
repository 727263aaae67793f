"""The nominal model against the robots of an uncertainty box, for any generated robot.

TDC and TDROC estimate the unknown dynamics from the last sample (17); the estimate
converges only if the nominal inertia M̂ is not too far from the true M:
‖M⁻¹ M̂ − I‖₂ < 1 (Roy et al. 2017, the condition under (17)). ROC needs bounds
α ≥ ‖M⁻¹ M̂ − I‖₂ and φ ≥ ‖M⁻¹ (H − Ĥ)‖ over its predefined box (the paper's "30 % above
nominal"). Both are sampled here on the generated model:

* the box perturbs each inertial parameter (:func:`inertial_keys`: those the kinematics
  does not depend on, the ones a payload changes; Drishti's m, I, K, Iw) independently:
  :func:`tde_alpha` over the symmetric box ±``box`` (a three-level grid: lower face,
  centre, upper face), :func:`roc_bounds` over its corners above nominal (each parameter
  nominal or ``uncertainty`` above it). Every grid point and corner while there are at most
  :data:`EXHAUSTIVE_KEYS` parameters (Drishti: 81 and 16); beyond, :data:`SAMPLED_POINTS`
  of them (the two extreme ones and random others, fixed seed);
* configurations: the root's heading over :data:`HEADINGS`, the other bodies' yaws (a
  trailer's) within ±1 rad of it, everything else 0; wheel rates (ROC's φ) uniform up to
  ``max_rate``.

M and H are the generated paper form M̃, H̃ of (14) (``paper``) or the minimal form M̄, H̄
in the driven-wheel rates (``minimal``); the maxima are sampled maxima. The parameters are
checked first as the generated controllers check a nominal model (``ERR_BAD_NOMINAL``).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Mapping, Sequence
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from runtime.bindings.generated import RobotCode

Array = NDArray[np.float64]
HEADINGS = tuple(float(x) for x in np.linspace(-math.pi, math.pi, 9))
LEVELS = (-1.0, 0.0, 1.0)  # of the symmetric box: lower face, centre, upper face
EXHAUSTIVE_KEYS = 5  # every grid point / corner up to this many inertial parameters
SAMPLED_POINTS = 32  # beyond: this many (the two extremes and random ones)
ROC_ETAS = 4  # random wheel-rate vectors per (heading, corner) for φ
YAW_SPREAD = 1.0  # rad: other bodies' yaws about the root's


def inertial_keys(code: RobotCode, params: Mapping[str, float]) -> tuple[str, ...]:
    """The parameters the kinematics does not depend on (masses, inertias, first moments):
    the ones an uncertainty box or a payload changes, in the parameter table's order."""
    p = dict(params)
    rng = np.random.default_rng(3)
    q = rng.uniform(-1.0, 1.0, code.nq)
    eta = rng.uniform(-1.0, 1.0, code.nu)
    base = code.velocities(q, eta, p)
    keys = []
    for key in p:
        moved = {**p, key: p[key] * 1.5 + 0.1}
        if np.allclose(code.velocities(q, eta, moved), base, rtol=1e-14, atol=1e-14):
            keys.append(key)
    return tuple(keys)


def body_yaws(code: RobotCode) -> tuple[int, ...]:
    """Indices of the yaws of the bodies after the root (a trailer's): on a straight line
    every wheel angle turns, a body's yaw does not."""
    rate = code.velocities(np.zeros(code.nq), np.ones(code.nu), code.params)
    return tuple(i for i in code.dependent if i > 2 and abs(rate[i]) < 1e-9)


def checked(code: RobotCode, params: Mapping[str, float], label: str) -> dict[str, float]:
    """``params`` as floats in the parameter table's order; ``ValueError`` naming ``label``
    if one is missing or not finite, or if the generated controllers refuse them as a
    nominal model (positive masses and inertias, a positive-definite mass matrix)."""
    keys = tuple(code.params)
    missing = [k for k in keys if k not in params]
    if missing:
        raise ValueError(f"{label}: missing parameter(s) {', '.join(missing)}")
    out = {k: float(params[k]) for k in keys}
    for key, value in out.items():
        if not math.isfinite(value):
            raise ValueError(f"{label}: parameter '{key}' must be finite, got {value!r}")
    problem = nominal_problem(code, out)
    if problem is not None:
        raise ValueError(f"{label}: {problem}")
    return out


def nominal_problem(code: RobotCode, params: Mapping[str, float]) -> str | None:
    """What the generated controllers' configuration check says of ``params`` as a nominal
    model (its ``ERR_BAD_NOMINAL`` message), or None if it accepts them."""
    ctl = code.controllers
    info = code.controller_infos[0]
    config = ctl.Config(nominal=dict(params),
                        formulation=getattr(ctl, f"FORMULATION_{info.formulations[0].upper()}"))
    try:
        code.controller_class(info.name).check_config(config)
    except ctl.ControllerError as exc:
        if exc.field == "NOMINAL":
            return str(exc).split(": ", 1)[-1]
    return None


def mass_matrix(code: RobotCode, q: Array, p: Mapping[str, float], formulation: str) -> Array:
    """M̃(q) of (14) (``paper``) or M̄ = Sᵀ M S (``minimal``) at parameters ``p``."""
    if formulation not in code.formulations:
        raise ValueError(f"formulation must be one of {', '.join(code.formulations)}, got "
                         f"{formulation!r}")
    if formulation == "paper":
        return np.asarray(code.model.mass_matrix(q, p), dtype=np.float64)
    return np.asarray(code.model.minimal_mass_matrix(q, p), dtype=np.float64)


def bias_difference(code: RobotCode, q: Array, eta: Array, p: Mapping[str, float],
                    nominal: Mapping[str, float], formulation: str) -> Array:
    """H(q, q̇; p) − Ĥ(q, q̇) at the wheel rates ``eta`` (q̇ = S(q) η at ``p``)."""
    if formulation == "paper":
        qdot = code.velocities(q, eta, dict(p))
        return np.asarray(code.model.bias_forces(q, qdot, p)
                          - code.model.bias_forces(q, qdot, nominal))
    return np.asarray(code.model.minimal_bias_forces(q, eta, p)
                      - code.model.minimal_bias_forces(q, eta, nominal))


def configurations(code: RobotCode) -> Iterator[Array]:
    """q at each of :data:`HEADINGS`: the root's heading, the other bodies' yaws within
    ±:data:`YAW_SPREAD` of it (fixed seed), every other coordinate 0."""
    rng = np.random.default_rng(11)
    yaws = body_yaws(code)
    for theta in HEADINGS:
        q = np.zeros(code.nq)
        q[2] = theta
        for i in yaws:
            q[i] = theta + rng.uniform(-YAW_SPREAD, YAW_SPREAD)
        yield q


def _points(count: int, levels: Sequence[float]) -> list[tuple[float, ...]]:
    """Every combination of ``levels`` over ``count`` parameters (in the order of
    ``itertools.product``), or, beyond :data:`EXHAUSTIVE_KEYS` parameters, the all-lowest,
    the all-highest and random ones (:data:`SAMPLED_POINTS` in all, fixed seed)."""
    if count <= EXHAUSTIVE_KEYS:
        return list(itertools.product(levels, repeat=count))
    rng = np.random.default_rng(5)
    out = [(levels[0],) * count, (levels[-1],) * count]
    out += [tuple(float(x) for x in rng.choice(levels, size=count))
            for _ in range(SAMPLED_POINTS - 2)]
    return out


def tde_alpha(
    code: RobotCode,
    nominal: Mapping[str, float],
    box: float = 0.3,
    *,
    true_params: Mapping[str, float] | None = None,
    formulation: str = "minimal",
) -> tuple[float, dict[str, float], float]:
    """(α = max ‖M(p)⁻¹ M̂ − I‖₂ over the true robots p within ±``box`` of ``true_params``
    (default: the nominal) on each inertial parameter, the p where it is reached, the
    heading there); no check of α. ``ValueError`` for a bad box or parameters, or a box
    that holds a robot the controllers would not accept as a model."""
    if not (math.isfinite(box) and 0.0 <= box < 1.0):
        raise ValueError(f"box must be in [0, 1), got {box!r}")
    nom = checked(code, nominal, "nominal")
    ref = checked(code, true_params if true_params is not None else nominal, "true_params")
    keys = inertial_keys(code, ref)
    worst: tuple[float, dict[str, float], float] = (-1.0, ref, 0.0)
    qs = list(configurations(code))
    for levels in _points(len(keys), LEVELS):
        p = {**ref, **{k: ref[k] * (1.0 + box * lv) for k, lv in zip(keys, levels, strict=True)}}
        problem = nominal_problem(code, p)
        if problem is not None:
            raise ValueError(
                f"the box ±{box:.0%} around the true parameters contains a robot whose mass "
                f"matrix is not positive definite ({p}): {problem}"
            )
        for q in qs:
            m_true = mass_matrix(code, q, p, formulation)
            m_hat = mass_matrix(code, q, nom, formulation)
            dev = np.linalg.solve(m_true, m_hat) - np.eye(len(m_hat))
            alpha = float(np.linalg.norm(dev, 2))
            if alpha > worst[0]:
                worst = (alpha, p, float(q[2]))
    return worst


def check_tde(
    code: RobotCode,
    nominal: Mapping[str, float],
    box: float = 0.3,
    *,
    true_params: Mapping[str, float] | None = None,
    formulation: str = "minimal",
) -> float:
    """α of :func:`tde_alpha`; ``ValueError`` if the TDE condition α < 1 fails.

    ``nominal``: the controller's model. ``true_params``: the centre of the box of true
    robots (default: the nominal itself). ``box``: relative half-width of every inertial
    parameter (0.3 = ±30 %)."""
    alpha, where, theta = tde_alpha(code, nominal, box, true_params=true_params,
                                    formulation=formulation)
    if not alpha < 1.0:
        worst = ", ".join(f"{k}={where[k]:.4g}" for k in inertial_keys(code, where))
        centre = "the nominal" if true_params is None else "true_params"
        raise ValueError(
            f"nominal model fails the TDE condition ||M^-1 Mhat - I|| < 1 ({formulation} "
            f"formulation): alpha = {alpha:.3f} at {worst}, theta={theta:.3f} (true "
            f"parameters within ±{box:.0%} of {centre}). The nominal inertia is too far from "
            "the robot's: choose it closer (roughly, 0 < M-hat < 2 M for every robot in the box)."
        )
    return alpha


def roc_bounds(code: RobotCode, nominal: Mapping[str, float], uncertainty: float,
               formulation: str, max_rate: float) -> tuple[float, float]:
    """(α, φ) for ROC: α = max ‖M⁻¹ M̂ − I‖₂ and φ = max ‖M⁻¹ (H − Ĥ)‖ over the corners of
    the box where every inertial parameter is nominal or ``uncertainty`` above it, over
    :func:`configurations` and :data:`ROC_ETAS` random wheel-rate vectors up to
    ``max_rate`` per corner (fixed seed)."""
    return _roc_bounds(code, tuple(nominal.items()), uncertainty, formulation, max_rate)


@lru_cache(maxsize=64)
def _roc_bounds(code: RobotCode, nominal_items: tuple[tuple[str, float], ...],
                uncertainty: float, formulation: str, max_rate: float) -> tuple[float, float]:
    """:func:`roc_bounds` once per nominal model (it samples a box, about as long as a run;
    a campaign's ROC runs share a few nominal models)."""
    nominal = dict(nominal_items)
    keys = inertial_keys(code, nominal)
    alpha, phi = 0.0, 0.0
    rng = np.random.default_rng(7)
    corners = [{**nominal, **{k: nominal[k] * (1 + uncertainty * up)
                              for k, up in zip(keys, levels, strict=True)}}
               for levels in _corner_levels(len(keys))]
    for q in configurations(code):
        m_hat = mass_matrix(code, q, nominal, formulation)
        for p in corners:
            inv = np.linalg.inv(mass_matrix(code, q, p, formulation))
            alpha = max(alpha, float(np.linalg.norm(inv @ m_hat - np.eye(len(m_hat)), 2)))
            for eta in rng.uniform(-max_rate, max_rate, size=(ROC_ETAS, code.nu)):
                dh = bias_difference(code, q, eta, p, nominal, formulation)
                phi = max(phi, float(np.linalg.norm(inv @ dh)))
    return alpha, phi


def _corner_levels(count: int) -> list[tuple[int, ...]]:
    """0/1 (nominal / above) per parameter for each corner: parameter i above in corner
    ``mask`` when bit i of ``mask`` is set, every corner while there are at most
    :data:`EXHAUSTIVE_KEYS` parameters, else :func:`_points`'s sample."""
    if count <= EXHAUSTIVE_KEYS:
        return [tuple((mask >> i) & 1 for i in range(count)) for mask in range(2**count)]
    return [tuple(int(x) for x in levels) for levels in _points(count, (0.0, 1.0))]


def schedule_tde(code: RobotCode, nominal: Mapping[str, float],
                 loaded: Sequence[Mapping[str, float]], formulation: str) -> float:
    """max ‖M(q)⁻¹ M̂(q) − I‖₂ between the nominal model and each of the simulated robot's
    parameter sets ``loaded`` (e.g. with its payloads), over :func:`configurations`."""
    worst = 0.0
    for q in configurations(code):
        m_hat = mass_matrix(code, q, nominal, formulation)
        for p in loaded:
            m = mass_matrix(code, q, p, formulation)
            gap = np.linalg.solve(m, m_hat) - np.eye(len(m))
            worst = max(worst, float(np.linalg.norm(gap, 2)))
    return worst
