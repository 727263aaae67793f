"""Drishti's model report (``MODEL.md``): what was derived, what the paper prints, and why
they differ.

:func:`model_report_context` assembles everything the report shows — the derived equations
as LaTeX, the lumped relations with their assumptions, one verdict per printed equation
(from :mod:`modeling.robots.drishti.paper`), the robot's parameters and, optionally, the
generated code's operation counts and the derivation time — and
:func:`render_model_report` lays it out with ``model_report.md.jinja`` (beside this file).
The template does layout only; every number and formula is produced here. The output is
deterministic: no timestamps, no absolute paths, and nothing that depends on the hash seed.

``python -m codegen`` calls :func:`render` because the model names this module in
``RobotModel.docs["report"]``; codegen itself never imports a robot.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import sympy as sp

from modeling import rendering
from modeling.robots.drishti import model as wmr
from modeling.robots.drishti.paper import display, symbols
from modeling.robots.drishti.paper.transcriptions import PRINTED_PARAMETERS
from modeling.robots.drishti.paper.verdicts import judgements
from modeling.robots.drishti.parameters import LUMPED

TEMPLATE_DIR = Path(__file__).resolve().parent
TEMPLATE = "model_report.md.jinja"
SOURCE = f"{wmr.SOURCE}, modeling/lagrange.py, modeling/robots/drishti/paper/"


def _latex(expr: sp.Basic) -> str:
    return sp.latex(expr, symbol_names=display.LATEX_NAMES)


def _cell(text: str) -> str:
    """A Markdown table cell: one line, no unescaped pipe."""
    return " ".join(text.split()).replace("|", "\\|")


def _block(caption: str, latex: str) -> dict[str, str]:
    return {"caption": caption, "latex": latex}


def _tidy_matrix(mat: sp.Matrix, on_manifold: bool = False) -> sp.Matrix:
    f = display.in_printed_terms if on_manifold else display.tidy
    return mat.applyfunc(f)


def _reduced_mass_with_k(s: Any) -> tuple[sp.Matrix, list[tuple[sp.Symbol, sp.Expr]]]:
    """M̃ of (14) with its coupling entries named k1…k5 as in the paper.

    k1…k4 are the entries (1,4), (1,5), (2,4), (2,5) and k5 the entry (3,5); every entry
    equal to ±k_i is shown as ±k_i (found by comparison, not assumed).
    """
    mt = s.reduced_mass_matrix
    names = (symbols.k1, symbols.k2, symbols.k3, symbols.k4, symbols.k5)
    positions = ((0, 3), (0, 4), (1, 3), (1, 4), (2, 4))
    defs = [(k, mt[i, j]) for k, (i, j) in zip(names, positions, strict=True)]
    shown = sp.zeros(mt.rows, mt.cols)
    for i in range(mt.rows):
        for j in range(mt.cols):
            entry = mt[i, j]
            shown[i, j] = display.tidy(entry)
            for k, v in defs:
                if entry != 0 and sp.expand(entry - v) == 0:
                    shown[i, j] = k
                elif entry != 0 and sp.expand(entry + v) == 0:
                    shown[i, j] = -k
    return shown, [(k, display.tidy(v)) for k, v in defs]


def _derived_sections() -> list[dict[str, Any]]:
    s = wmr.wmr_system()
    q = sp.Matrix(s.q)
    eta = sp.Matrix(s.eta)
    eta_dot = sp.Matrix(s.eta_dot)
    lam = symbols.LAMBDA
    tau = wmr.tau
    sections: list[dict[str, Any]] = []

    sections.append({
        "title": "Equations of motion (9)",
        "text": (
            "Euler–Lagrange equations of the kinetic energy below, with the rolling "
            "constraints (6)–(8) as A(q) q̇ = 0 and their multipliers λ. Generalised "
            "coordinates q = (x_c, y_c, θ, θ_r, θ_l): C = (x_c, y_c), the heading θ and the "
            "wheel angles."
        ),
        "blocks": [
            _block("Kinetic energy (lumped parameters)",
                   "T = " + _latex(display.tidy(s.kinetic_energy))),
            _block("Equation (9)",
                   r"M(q)\,\ddot{q} + H(q,\dot{q}) = B\,\tau - A^{T}(q)\,\lambda,\qquad "
                   rf"q = {_latex(q.T)}^{{T}},\quad \lambda = {_latex(lam.T)}^{{T}},"
                   rf"\quad \tau = {_latex(tau.T)}^{{T}}"),
            _block("Mass matrix", "M(q) = " + _latex(_tidy_matrix(s.mass_matrix))),
            _block("Coriolis and centripetal terms",
                   r"H(q,\dot{q}) = " + _latex(_tidy_matrix(s.bias))),
            _block("Input matrix", "B = " + _latex(s.input_matrix)),
            _block("Constraint matrix, A(q) q̇ = 0 is (6)–(8)",
                   "A(q) = " + _latex(_tidy_matrix(s.constraint_matrix))),
        ],
    })

    lam_eta = s.multipliers_given_accelerations(tau)
    sections.append({
        "title": "Constraint forces (10)–(12)",
        "text": (
            "The dependent rows (1)–(3) of (9) solved for λ, with q̈ = S η̇ + Ṡ η (the "
            "constraints differentiated once). Written, like the paper, with "
            "θ̇ = r(θ̇_r − θ̇_l)/b and θ̈ = r(θ̈_r − θ̈_l)/b, which hold on the constraint "
            "manifold. I − 2Kd + md² is the yaw inertia about the axle midpoint."
        ),
        "blocks": [
            _block(f"({10 + i})", rf"\lambda_{{{i + 1}}} = "
                   + _latex(display.in_printed_terms(lam_eta[i])))
            for i in range(3)
        ],
    })

    shown, k_defs = _reduced_mass_with_k(s)
    sections.append({
        "title": "Multiplier-free form (14)",
        "text": (
            "Rows 1–3: (1)–(3) with the multipliers (10)–(12) substituted; rows 4–5: (4)–(5) "
            "with the multipliers solved from (1)–(3). The result is not symmetric "
            "(M̃₄₁ = −M̃₁₄ …). H̃ is shown on the constraint manifold."
        ),
        "blocks": [
            _block("Equation (14)",
                   r"\tilde{M}(q)\,\ddot{q} + \tilde{H}(q,\dot{q}) = u = B\,\tau"),
            _block("Mass matrix", r"\tilde{M}(q) = " + _latex(shown)),
            _block("Coupling entries", r",\quad ".join(
                f"{_latex(k)} = {_latex(v)}" for k, v in k_defs)),
            _block("Velocity terms", r"\tilde{H}(q,\dot{q}) = "
                   + _latex(_tidy_matrix(s.reduced_bias.subs(s.on_manifold), True))),
        ],
    })

    sections.append({
        "title": "Kinematics (31) and the minimal form",
        "text": (
            "q̇ = S(q) η with η = (θ̇_r, θ̇_l): the first three rows of S are the kinematics "
            "(31). Projecting (9) on S removes λ and gives the two-dimensional minimal form "
            "that the simulation integrates."
        ),
        "blocks": [
            _block("Null space of A (A S = 0)",
                   rf"\dot{{q}} = S(q)\,\eta,\quad \eta = {_latex(eta.T)}^{{T}},\quad "
                   f"S(q) = {_latex(_tidy_matrix(s.null_space))}"),
            _block("Minimal form",
                   r"\bar{M}\,\dot{\eta} + \bar{H}(q,\eta) = S^{T}B\,\tau,\qquad "
                   r"\bar{M} = S^{T} M S,\quad \bar{H} = S^{T}(M\dot{S}\eta + H),\quad "
                   rf"\dot{{\eta}} = {_latex(eta_dot.T)}^{{T}},\quad "
                   rf"S^{{T}}B = {_latex(s.minimal_input_matrix)}"),
            _block("Minimal mass matrix (constant)",
                   r"\bar{M} = " + _latex(_tidy_matrix(s.minimal_mass_matrix))),
            _block("Minimal velocity terms",
                   r"\bar{H} = " + _latex(_tidy_matrix(s.minimal_bias))),
        ],
    })
    return sections


def _lumped_section() -> dict[str, Any]:
    rel = wmr.lumped_relations(wmr.physical_bodies())
    on_axle = {wmr.x_P: 0, wmr.y_P: 0}
    relations = [
        _block(name, f"{_latex(sym)} = {_latex(rel[sym])}")
        for name, sym in (("total mass", wmr.m), ("yaw inertia about C", wmr.I_z),
                          ("first moment of mass behind C", wmr.K),
                          ("first moment of mass left of C", wmr.K_lat))
    ]
    m_axle = sp.simplify(rel[wmr.K].subs(on_axle).subs(wmr.m_P, wmr.m - 2 * wmr.m_w))
    paper_case = [
        _block("yaw inertia", f"{_latex(wmr.I_z)} = {_latex(rel[wmr.I_z].subs(on_axle))}"),
        _block("first moments", f"{_latex(wmr.K)} = {_latex(m_axle)},\\quad "
               f"{_latex(wmr.K_lat)} = 0"),
    ]
    assumptions = [
        "C = (x_c, y_c) lies on the robot's axis of symmetry, a distance d ahead of the axle "
        "midpoint (so that (6) is the axle's no-side-slip condition).",
        "Two wheels (mass m_w, inertia I_m about a vertical diameter, spin inertia I_w) sit on "
        "the axle at ±b/2 and roll without slipping on radius r.",
        "The platform (mass m_P, inertia I_P about its own centre of mass) has its centre of "
        "mass x_P ahead of the axle midpoint and y_P to its left.",
        "The paper's relation for I is the case x_P = y_P = 0 (platform centre of mass on "
        "the axle). The paper's model has K_lat = 0 (mass symmetric about the robot's "
        "axis); an off-axis payload makes K_lat ≠ 0.",
    ]
    return {
        "kinetic_energy": _latex(display.tidy(wmr.lumped_kinetic_energy(True))),
        "assumptions": assumptions,
        "relations": relations,
        "paper_case": paper_case,
    }


_SUPERSCRIPTS = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _unit(unit: str) -> str:
    """A unit of the parameter table as Markdown shows it: ``kg m^2`` → ``kg m²``."""
    return re.sub(r"\^(-?\d+)", lambda g: g.group(1).translate(_SUPERSCRIPTS), unit)


def _robot_rows(robot_lumped: dict[str, float]) -> tuple[list[dict[str, str]],
                                                         list[dict[str, str]]]:
    table = {p.key: p for p in LUMPED}
    rows = []
    for key in list(table) + sorted(set(robot_lumped) - set(table)):
        if key not in robot_lumped:
            continue
        printed = PRINTED_PARAMETERS.get(key)
        info = table.get(key)
        rows.append({
            "name": key,
            "value": f"{robot_lumped[key]:g}",
            "unit": _unit(info.unit) if info else "",
            "description": info.doc if info else "",
            "paper": "" if printed is None else f"{printed:g}",
        })
    derived: list[dict[str, str]] = []
    if {"m", "K", "I", "d"} <= set(robot_lumped):
        mass, k, inertia, d = (robot_lumped[x] for x in ("m", "K", "I", "d"))
        derived = [
            {"name": "centre of mass behind C, K/m", "value": f"{1000 * k / mass:.1f} mm"},
            {"name": "K implied by the paper's I relation (x_P = y_P = 0), m d",
             "value": f"{mass * d:.4g} kg m"},
            {"name": "yaw inertia about the centre of mass, I − K²/m",
             "value": f"{inertia - k * k / mass:.4g} kg m²"},
            {"name": "yaw inertia about the axle midpoint, I − 2Kd + m d²",
             "value": f"{inertia - 2 * k * d + mass * d * d:.4g} kg m²"},
        ]
    return rows, derived


def model_report_context(
    robot_lumped: dict[str, float],
    robot_name: str,
    derivation_seconds: float | None,
    op_counts: dict[str, str],
    warnings: tuple[str, ...] = (),
) -> dict[str, Any]:
    """Everything the report shows, as strings ready for layout; ``warnings``: the physics
    audit's findings on the robot file (``modeling.audit``)."""
    judged = judgements()
    verdict_rows = [
        {"equation": j.transcription.equation, "verdict": j.verdict,
         "evidence": _cell(j.evidence)}
        for j in judged
    ]
    counts = {k: sum(1 for j in judged if j.verdict == k)
              for k in ("confirmed", "erratum", "reconstructed")}
    differences = [
        {
            "equation": j.transcription.equation,
            "verdict": j.verdict,
            "evidence": " ".join(j.evidence.split()),
            "printed_latex": j.printed_resolved_latex(),
            "derived_latex": j.as_verdict().derived_latex,
        }
        for j in judged
        if j.verdict != "confirmed"
    ]
    notes = [
        {"equation": j.transcription.equation,
         "note": " ".join(j.transcription.note.removeprefix("Note:").split())}
        for j in judged
        if j.verdict == "confirmed" and j.transcription.note.startswith("Note:")
    ]
    negated = [j.transcription.equation for j in judged if j.negated]
    parameters, derived_numbers = _robot_rows(robot_lumped)
    return {
        "preamble": list(rendering.preamble_lines(SOURCE, TEMPLATE_DIR, TEMPLATE)),
        "robot_name": robot_name,
        "derivation_seconds": (
            None if derivation_seconds is None else f"{derivation_seconds:.1f}"
        ),
        "sections": _derived_sections(),
        "lumped": _lumped_section(),
        "verdicts": verdict_rows,
        "verdict_counts": counts,
        "differences": differences,
        "notes": notes,
        "negated": negated,
        "parameters": parameters,
        "derived_numbers": derived_numbers,
        "op_counts": [{"function": k, "count": _cell(v)} for k, v in op_counts.items()],
        "warnings": [" ".join(w.split()) for w in warnings],
    }


def render_model_report(context: dict[str, Any]) -> str:
    """Lay out a context from :func:`model_report_context` as Markdown."""
    return rendering.render(TEMPLATE_DIR, TEMPLATE, **context)


def render(model: Any, robot: Any, op_counts: dict[str, str]) -> str:
    """The paper robot's MODEL.md (the generator's report hook, ``RobotModel.docs``)."""
    return render_model_report(model_report_context(robot.lumped, robot.name, None, op_counts,
                                                    getattr(robot, "warnings", ())))
