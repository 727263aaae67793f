"""The judge: a transcription's printed form against the derivation, sign slots solved.

Comparison
    For each transcription the printed form P(σ) and the derived form D are brought to the
    same variables: equations (1)–(8), (13) are compared as identities in (q, q̇, q̈, λ, τ)
    (constraint equations as linear forms in q̇: on the constraint manifold they would
    vanish identically); the multipliers (10)–(12) and H of (14) are compared on the
    constraint manifold, i.e. ẋ, ẏ, θ̇ ← S η and ẍ, ÿ, θ̈ ← S η̇ + Ṡ η with
    η = (θ̇_r, θ̇_l), which is what "utilizing the constraint equations (6)–(8)" means. An
    equation (``lhs = rhs``) may also match the negated derivation (the same equation);
    a quantity (λ1, M, S, …) must match as is.

    The residual P(σ) − D is expanded, reduced modulo sin² + cos² = 1
    (:func:`modeling.lagrange.trig_canonical`), cleared of (σ-free) denominators, and split
    into its coefficients as a polynomial in every non-slot symbol and sin θ, cos θ. Each
    coefficient is a polynomial in the slots that must vanish. Coefficients are grouped
    into connected components by the slots they share, and each component (a handful of
    slots) is solved by enumerating {±1}^k; the best assignment minimises the number of
    non-vanishing coefficients, then their total magnitude.

Verdicts
    ``confirmed``      some sign assignment makes printed and derived forms identical; the
                       evidence lists where a minus had to be restored.
    ``erratum``        no assignment does; the evidence gives printed − derived for the
                       best assignment (in the printed form's own terms where possible),
                       the terms that are not dimensionally homogeneous, and a one-line
                       explanation.
    ``reconstructed``  the printed text does not give the relation (K is "given in Nandy
                       et al."); the evidence says what was rebuilt and how the printed
                       numbers compare with it.
"""
from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import sympy as sp

from modeling.lagrange import ConstrainedSystem, trig_canonical
from modeling.robots.drishti import model as wmr
from modeling.robots.drishti.paper.display import (
    dimension_outliers,
    heading_coordinates,
    in_printed_terms,
    text,
    tidy,
    unit_text,
)
from modeling.robots.drishti.paper.transcriptions import Form, Transcription

VerdictKind = Literal["confirmed", "reconstructed", "erratum"]


@dataclass(frozen=True)
class Verdict:
    """The outcome for one printed equation (or one matrix of it)."""

    equation: str
    verdict: VerdictKind
    evidence: str
    derived_latex: str
    printed_latex: str



@dataclass(frozen=True)
class Judgement:
    """A verdict with the data behind it (for the report and the tests)."""

    transcription: Transcription
    verdict: VerdictKind
    evidence: str
    assignment: dict[sp.Symbol, int] = field(default_factory=dict)
    negated: bool = False  # the printed equation is the derived one times −1
    residual: sp.Matrix | None = None  # printed(best σ) − derived, on the comparison variables

    def as_verdict(self) -> Verdict:
        t = self.transcription
        return Verdict(
            equation=t.equation,
            verdict=self.verdict,
            evidence=self.evidence,
            derived_latex=t.derived.latex(in_printed_terms if t.on_manifold else tidy),
            printed_latex=t.printed_display if t.printed is None else t.printed.latex(),
        )

    def printed_resolved_latex(self) -> str:
        """The printed form with the chosen signs substituted for the slots."""
        t = self.transcription
        if t.printed is None:
            return t.printed_display
        p = t.printed
        subs = {s: sp.Integer(v) for s, v in self.assignment.items()}
        resolved = Form(
            p.rhs.subs(subs),
            None if p.lhs is None else p.lhs.subs(subs),
            p.label,
            tuple((k, v.subs(subs)) for k, v in p.definitions),
        )
        return resolved.latex()



def _manifold_substitution(s: ConstrainedSystem) -> dict[sp.Symbol, sp.Expr]:
    """ẋ, ẏ, θ̇ ← S η and ẍ, ÿ, θ̈ ← S η̇ + Ṡ η."""
    acc = s.null_space * sp.Matrix(s.eta_dot) + s.null_space_rate
    subs: dict[sp.Symbol, sp.Expr] = dict(s.on_manifold)
    for i in s.dependent:
        subs[s.qddot[i]] = acc[i]
    return subs


def _coefficients(entry: sp.Expr, slots: set[sp.Symbol]) -> list[sp.Expr]:
    """The coefficients (polynomials in the slots) of an entry of the residual."""
    e = sp.expand(entry)
    if e == 0:
        return []
    e = sp.expand(sp.numer(sp.together(e)))
    e = trig_canonical(e)
    if e == 0:
        return []
    gens: list[sp.Expr] = sorted(
        (e.free_symbols - slots), key=sp.default_sort_key
    ) + sorted(e.atoms(sp.sin, sp.cos), key=sp.default_sort_key)
    if not gens:
        return [e]
    return [c for c in sp.Poly(e, *gens).coeffs() if c != 0]


def _components(eqs: list[sp.Expr]) -> list[tuple[list[sp.Symbol], list[sp.Expr]]]:
    """Group coefficient equations by the slots they share (union–find)."""
    parent: dict[sp.Symbol, sp.Symbol] = {}

    def find(a: sp.Symbol) -> sp.Symbol:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    syms_of = [sorted(e.free_symbols, key=sp.default_sort_key) for e in eqs]
    for syms in syms_of:
        for s_ in syms:
            parent.setdefault(s_, s_)
        for a, c in itertools.pairwise(syms):
            ra, rc = find(a), find(c)
            if ra != rc:
                parent[rc] = ra
    groups: dict[sp.Symbol | None, list[sp.Expr]] = {}
    for e, syms in zip(eqs, syms_of, strict=True):
        groups.setdefault(find(syms[0]) if syms else None, []).append(e)
    out = []
    for root, group in groups.items():
        members = [] if root is None else sorted(
            (s_ for s_ in parent if find(s_) == root), key=sp.default_sort_key
        )
        out.append((members, group))
    return out


@dataclass(frozen=True)
class _Match:
    assignment: dict[sp.Symbol, int]
    failures: int
    magnitude: sp.Expr


def _solve_signs(eqs: list[sp.Expr], slots: Sequence[sp.Symbol]) -> _Match:
    """The sign assignment that makes the most coefficient equations vanish."""
    assignment: dict[sp.Symbol, int] = {}
    failures = 0
    magnitude: sp.Expr = sp.Integer(0)
    for members, group in _components(eqs):
        # Rank: fewest non-vanishing coefficients, then their total magnitude, then the
        # most minus signs restored (a slot marks where the extraction may have lost one;
        # this tie-break only decides between equally wrong readings of an erratum).
        best: tuple[int, sp.Expr, int, tuple[int, ...]] | None = None
        for signs in itertools.product((-1, 1), repeat=len(members)):
            subs = dict(zip(members, signs, strict=True))
            vals = [e.xreplace(subs) for e in group]
            fails = sum(1 for v in vals if v != 0)
            size = sum((abs(v) for v in vals), sp.Integer(0))
            key = (fails, size, signs.count(1))
            if best is None or key < best[:3]:
                best = (*key, signs)
        assert best is not None
        assignment.update(zip(members, best[3], strict=True))
        failures += best[0]
        magnitude += best[1]
    for s_ in slots:
        assignment.setdefault(s_, 1)  # a slot no coefficient depends on: read as printed
    return _Match(assignment, failures, magnitude)


def _matrix_text(res: sp.Matrix, fmt: Callable[[sp.Expr], str]) -> str:
    if res.shape == (1, 1):
        return fmt(res[0, 0])
    parts = [
        f"({i + 1},{j + 1}): {fmt(res[i, j])}"
        for i in range(res.rows)
        for j in range(res.cols)
        if res[i, j] != 0
    ]
    return "; ".join(parts)


def _slot_text(t: Transcription, assignment: dict[sp.Symbol, int]) -> str:
    restored = [label for s_, label in t.slots if assignment.get(s_, 1) == -1]
    if not t.slots:
        return "no sign slots: equal exactly as printed"
    if not restored:
        return f"all {len(t.slots)} sign slots read +"
    return (
        f"minus restored at {len(restored)} of {len(t.slots)} slots: "
        + ", ".join(f"«{x}»" for x in restored)
    )


def judge(t: Transcription) -> Judgement:
    """Compare one transcription with the derivation (see the module docstring)."""
    if t.printed is None:
        return Judgement(t, "reconstructed", t.reconstruction)
    s = wmr.wmr_system()
    subs = _manifold_substitution(s) if t.on_manifold else {}
    printed = t.printed.residual().subs(subs)
    derived = t.derived.residual().subs(subs)
    slot_syms = [x for x, _ in t.slots]
    slot_set = set(slot_syms)
    negations = (1, -1) if t.printed.lhs is not None else (1,)
    best: tuple[_Match, int] | None = None
    # On the manifold, coefficients are taken in the heading coordinates, so that a printed
    # term meets the derived term it stands for (this only matters for ranking readings of
    # an erratum: the change of variables is invertible).
    coords = heading_coordinates() if t.on_manifold else {}
    for sign in negations:
        res = (printed - sign * derived).subs(coords)
        eqs = [c for e in res for c in _coefficients(e, slot_set)]
        match = _solve_signs(eqs, slot_syms)
        if best is None or (match.failures, match.magnitude) < (best[0].failures,
                                                               best[0].magnitude):
            best = (match, sign)
        if match.failures == 0:
            break
    assert best is not None
    match, sign = best
    values = {k: sp.Integer(v) for k, v in match.assignment.items()}
    residual = (printed.subs(values) - sign * derived).applyfunc(
        lambda e: trig_canonical(sp.expand(e))
    )
    slot_info = _slot_text(t, match.assignment)
    negation = " The printed equation is the derived one multiplied by −1." if sign == -1 else ""
    if match.failures == 0 and all(e == 0 for e in residual):
        evidence = f"Identical to the derivation; {slot_info}.{negation}"
        if t.on_manifold:
            evidence += " Compared on the constraint manifold."
        if t.note and t.note.startswith("Note:"):
            evidence += " " + t.note
        return Judgement(t, "confirmed", evidence, match.assignment, sign == -1,
                         residual)
    fmt = in_printed_terms if t.on_manifold else tidy
    diff = _matrix_text(residual, lambda e: f"`{text(fmt(e))}`")
    outliers = [
        o
        for e in t.printed.residual().subs(values)
        for o in dimension_outliers(e)
    ]
    dims = ""
    if outliers:
        dims = " Not dimensionally homogeneous: " + ", ".join(
            f"`{text(o)}` [{unit_text(o)}]" for o in outliers
        ) + "."
    if t.slots:
        head = (
            f"No sign assignment matches (the best leaves {match.failures} coefficient(s) "
            f"non-zero). Best reading ({slot_info}{'; negated' if sign == -1 else ''}): "
        )
    else:
        head = "Differs as printed (no sign could have been lost here): "
    evidence = f"{head}printed − derived = {diff}.{dims} {t.note}".strip()
    return Judgement(t, "erratum", evidence, match.assignment, sign == -1, residual)

