"""The paper's printed equations, transcribed, and a verdict on each against the derivation.

The specification (Roy et al. 2017) reaches us as a text extraction that lost almost every
minus sign and flattened sub- and superscripts (see ``/work/shared/paper/READING.md``). A
printed equation is therefore never evidence by itself: this module transcribes each of
(1)–(14), (31) and the lumped relations for m, I and K *as best read*, and lets the
derivation of :mod:`modeling.wmr` decide.

Transcription
    Every printed sign that is visible (a ``+``, an ``=``) is kept. Wherever the extraction
    shows no operator between two terms, or a matrix entry could have carried a leading
    minus, the transcription multiplies by a *sign slot* ``σ_k ∈ {+1, −1}`` (a
    ``sympy.Symbol`` named ``sigma_k``). Diagonal inertias (m, I, I_w) and the 0/1 entries
    of B are read as printed. Auxiliary printed definitions (Ω1, Ω2 of (11)–(12), k1…k5
    of (14)) are kept as symbols in the display and substituted before comparing.

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

Only the derived side comes from the engine; nothing here is hand-derived. Running
:func:`verdicts` takes about three seconds (the engine's derivation dominates).
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import sympy as sp

from modeling import wmr
from modeling.lagrange import ConstrainedSystem, trig_canonical

VerdictKind = Literal["confirmed", "reconstructed", "erratum"]

# ---------------------------------------------------------------------------------------
# Symbols
# ---------------------------------------------------------------------------------------
x_c, y_c, theta, theta_r, theta_l = wmr.q
xd, yd, thd, thd_r, thd_l = wmr.qdot
xdd, ydd, thdd, thdd_r, thdd_l = wmr.qddot
tau_r, tau_l = wmr.tau
m, I, K, I_w, r, b, d = wmr.m, wmr.I_z, wmr.K, wmr.I_w, wmr.r, wmr.b, wmr.d
lam1, lam2, lam3 = sp.symbols("lambda_1 lambda_2 lambda_3", real=True)
LAMBDA = sp.Matrix([lam1, lam2, lam3])
Omega1, Omega2 = sp.symbols("Omega_1 Omega_2", real=True)
k1, k2, k3, k4, k5 = sp.symbols("k_1 k_2 k_3 k_4 k_5", real=True)
SIN, COS = sp.sin(theta), sp.cos(theta)

# Shorthands of the printed (10)–(14), used to present residuals in the printed terms.
WHEEL_ACC_SUM = sp.Symbol("Sigma_acc", real=True)  # θ̈_r + θ̈_l
WHEEL_SQ_DIFF = sp.Symbol("Delta_sq", real=True)  # θ̇_r² − θ̇_l²
_WHEEL_RATE_SUM = sp.Dummy("P")  # θ̇_r + θ̇_l, eliminated again

LATEX_NAMES: dict[sp.Symbol, str] = {
    WHEEL_ACC_SUM: r"(\ddot{\theta}_{r} + \ddot{\theta}_{l})",
    WHEEL_SQ_DIFF: r"(\dot{\theta}_{r}^{2} - \dot{\theta}_{l}^{2})",
}

_TEXT_NAMES: dict[sp.Symbol, str] = {
    x_c: "x", y_c: "y", theta: "θ", theta_r: "θr", theta_l: "θl",
    xd: "ẋ", yd: "ẏ", thd: "θ̇", thd_r: "θ̇r", thd_l: "θ̇l",
    xdd: "ẍ", ydd: "ÿ", thdd: "θ̈", thdd_r: "θ̈r", thdd_l: "θ̈l",
    lam1: "λ1", lam2: "λ2", lam3: "λ3", tau_r: "τr", tau_l: "τl",
    I_w: "Iw", WHEEL_ACC_SUM: "(θ̈r+θ̈l)", WHEEL_SQ_DIFF: "(θ̇r²−θ̇l²)",
    wmr.m_P: "mP", wmr.m_w: "mw", wmr.I_P: "IP", wmr.I_m: "Im", wmr.x_P: "xP", wmr.y_P: "yP",
}

# Dimensions (mass, length, time) for the homogeneity check of printed terms.
_MASS, _LENGTH, _TIME = sp.symbols("MASS LENGTH TIME", positive=True)
_DIMENSIONS: dict[sp.Symbol, sp.Expr] = {
    m: _MASS, wmr.m_P: _MASS, wmr.m_w: _MASS,
    K: _MASS * _LENGTH, wmr.K_lat: _MASS * _LENGTH,
    I: _MASS * _LENGTH**2, I_w: _MASS * _LENGTH**2,
    wmr.I_P: _MASS * _LENGTH**2, wmr.I_m: _MASS * _LENGTH**2,
    r: _LENGTH, b: _LENGTH, d: _LENGTH, wmr.x_P: _LENGTH, wmr.y_P: _LENGTH,
    x_c: _LENGTH, y_c: _LENGTH, theta: sp.S.One, theta_r: sp.S.One, theta_l: sp.S.One,
    xd: _LENGTH / _TIME, yd: _LENGTH / _TIME,
    thd: 1 / _TIME, thd_r: 1 / _TIME, thd_l: 1 / _TIME,
    xdd: _LENGTH / _TIME**2, ydd: _LENGTH / _TIME**2,
    thdd: 1 / _TIME**2, thdd_r: 1 / _TIME**2, thdd_l: 1 / _TIME**2,
    lam1: _MASS * _LENGTH / _TIME**2, lam2: _MASS * _LENGTH / _TIME**2,
    lam3: _MASS * _LENGTH / _TIME**2,
    tau_r: _MASS * _LENGTH**2 / _TIME**2, tau_l: _MASS * _LENGTH**2 / _TIME**2,
}

# The numbers the paper prints for Drishti (Section "Experimental results").
PRINTED_PARAMETERS: dict[str, float] = {
    "m": 36.0, "d": 0.12, "r": 0.096, "b": 0.414, "I": 5.72, "Iw": 0.07, "K": 0.34,
}


# ---------------------------------------------------------------------------------------
# Data
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Verdict:
    """The outcome for one printed equation (or one matrix of it)."""

    equation: str
    verdict: VerdictKind
    evidence: str
    derived_latex: str
    printed_latex: str


@dataclass(frozen=True)
class Form:
    """An equation ``lhs = rhs`` (``lhs`` given) or a quantity ``label = rhs`` (``lhs`` None).

    Scalars are 1×1 matrices. ``definitions`` are printed auxiliary symbols (Ω1, k1, …),
    substituted before comparing and shown after the form.
    """

    rhs: sp.Matrix
    lhs: sp.Matrix | None = None
    label: str = ""
    definitions: tuple[tuple[sp.Symbol, sp.Expr], ...] = ()

    def expanded(self) -> Form:
        """The form with its definitions substituted."""
        subs = dict(self.definitions)
        return Form(
            self.rhs.subs(subs),
            None if self.lhs is None else self.lhs.subs(subs),
            self.label,
        )

    def residual(self) -> sp.Matrix:
        """lhs − rhs for an equation, the value for a quantity (definitions substituted)."""
        e = self.expanded()
        return e.rhs if e.lhs is None else e.lhs - e.rhs

    def latex(self, tidy: Callable[[sp.Expr], sp.Expr] | None = None) -> str:
        def show(mat: sp.Matrix) -> str:
            if tidy is not None:
                mat = mat.applyfunc(tidy)
            obj: sp.Basic = mat[0, 0] if mat.shape == (1, 1) else mat
            return sp.latex(obj, symbol_names=LATEX_NAMES)

        head = self.label if self.lhs is None else show(self.lhs)
        text = f"{head} = {show(self.rhs)}"
        if self.definitions:
            defs = ",\\quad ".join(
                f"{sp.latex(s)} = {sp.latex(v, symbol_names=LATEX_NAMES)}"
                for s, v in self.definitions
            )
            text += f",\\qquad {defs}"
        return text


@dataclass(frozen=True)
class Transcription:
    """One printed equation as best read, and what the derivation says it should be."""

    equation: str
    source: str  # the extracted text it was read from (cleaned of the other column)
    printed: Form | None  # None: not printed, reconstructed from the derivation
    derived: Form
    slots: tuple[tuple[sp.Symbol, str], ...] = ()  # (σ_k, the term it signs)
    on_manifold: bool = False
    note: str = ""  # the one-line explanation shown when the verdict is an erratum
    reconstruction: str = ""  # what was rebuilt, for printed=None
    printed_display: str = ""  # LaTeX of what is printed instead, for printed=None


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


class _Slots:
    """Hands out σ_1, σ_2, … for one transcription and remembers what each one signs."""

    def __init__(self) -> None:
        self.items: list[tuple[sp.Symbol, str]] = []

    def __call__(self, label: str) -> sp.Symbol:
        s = sp.Symbol(f"sigma_{len(self.items) + 1}", real=True)
        self.items.append((s, label))
        return s

    def done(self) -> tuple[tuple[sp.Symbol, str], ...]:
        return tuple(self.items)


def _col(*entries: sp.Expr) -> sp.Matrix:
    return sp.Matrix(list(entries))


def _one(e: sp.Expr) -> sp.Matrix:
    return sp.Matrix([[e]])


# ---------------------------------------------------------------------------------------
# Presentation helpers (no mathematics is decided here)
# ---------------------------------------------------------------------------------------
def text(expr: sp.Basic) -> str:
    """A short plain-text rendering with the paper's letters (θ̇r, λ2, …)."""
    names = {s: sp.Symbol(n) for s, n in _TEXT_NAMES.items()}
    out = sp.sstr(expr.xreplace(names))
    return out.replace("**", "^").replace("*", "·")


def _heading_coordinates() -> dict[sp.Symbol, sp.Expr]:
    """θ̈r, θ̈l, θ̇r, θ̇l in terms of (θ̈r + θ̈l, θ̈) and (θ̇r + θ̇l, θ̇): an invertible change
    of variables on the manifold, in which each printed term of (10)–(14) is one monomial."""
    p = _WHEEL_RATE_SUM
    return {
        thdd_r: (WHEEL_ACC_SUM + b * thdd / r) / 2,
        thdd_l: (WHEEL_ACC_SUM - b * thdd / r) / 2,
        thd_r: (p + b * thd / r) / 2,
        thd_l: (p - b * thd / r) / 2,
    }


def in_printed_terms(expr: sp.Expr) -> sp.Expr:
    """Rewrite an expression in the wheel variables with the printed shorthands.

    On the constraint manifold θ̇ = r(θ̇r − θ̇l)/b and θ̈ = r(θ̈r − θ̈l)/b; (10)–(14) write
    their right-hand sides with θ̈, θ̇², (θ̈r + θ̈l) and (θ̇r² − θ̇l²). Expressions that do
    not fit (a (θ̇r + θ̇l)² term) are returned collected but otherwise unchanged.
    """
    p = _WHEEL_RATE_SUM
    e = sp.expand(expr.subs(_heading_coordinates()))
    c2 = e.coeff(p, 2)
    if c2 != 0:
        return tidy(expr)
    c1 = sp.expand(e.coeff(p, 1) / thd)
    if c1.has(p) or sp.denom(sp.together(c1)).has(thd):
        return tidy(expr)
    out = sp.expand(e.coeff(p, 0) + c1 * r * WHEEL_SQ_DIFF / b)
    return tidy(out)


def tidy(expr: sp.Expr) -> sp.Expr:
    """Collect on sin/cos and on the state variables, factoring each coefficient.

    An expression of the parameters alone is returned as it is."""
    original = expr
    expr = sp.expand(expr)
    if expr == 0:
        return expr
    keys: list[sp.Expr] = sorted(expr.atoms(sp.sin, sp.cos), key=sp.default_sort_key)
    state = [
        s for s in (*wmr.qddot, *wmr.qdot, WHEEL_ACC_SUM, WHEEL_SQ_DIFF, lam1, lam2, lam3,
                    tau_r, tau_l) if expr.has(s)
    ]
    keys += state
    if not keys:
        return original
    collected = sp.collect(expr, keys, evaluate=False)
    if set(collected) == {sp.S.One}:
        return sp.factor(expr)
    # Collect twice: first on monomials of the state, then each coefficient on sin/cos.
    state_mono = sp.collect(expr, state, evaluate=False) if state else {sp.S.One: expr}
    terms = []
    for mono, coeff in sorted(state_mono.items(), key=lambda kv: sp.default_sort_key(kv[0])):
        trig = sorted(coeff.atoms(sp.sin, sp.cos), key=sp.default_sort_key)
        if trig:
            parts = sp.collect(sp.expand(coeff), trig, evaluate=False)
            inner = sp.Add(*[sp.factor(c) * t for t, c in parts.items()])
        else:
            inner = sp.factor(coeff)
        terms.append(inner * mono)
    return sp.Add(*terms)


def dimension_outliers(expr: sp.Expr) -> list[sp.Expr]:
    """Terms of ``expr`` whose dimension differs from that of most terms (empty if homogeneous)."""
    trig = {a: sp.S.One for a in expr.atoms(sp.sin, sp.cos)}
    terms = sp.Add.make_args(sp.expand(expr))
    dims: list[sp.Expr] = []
    for t in terms:
        unit = sp.powsimp(t.xreplace(trig).xreplace(_DIMENSIONS))
        dims.append(unit.as_coeff_Mul()[1] if unit != 0 else sp.S.Zero)
    counts: dict[sp.Expr, int] = {}
    for u in dims:
        counts[u] = counts.get(u, 0) + 1
    if len(counts) <= 1:
        return []
    major = max(counts, key=lambda u: (counts[u], -len(str(u)), str(u)))
    return [t for t, u in zip(terms, dims, strict=True) if u != major]


def unit_text(term: sp.Expr) -> str:
    """The SI unit of a term, e.g. 'kg·m³/s²'."""
    trig = {a: sp.S.One for a in term.atoms(sp.sin, sp.cos)}
    unit = sp.powsimp(term.xreplace(trig).xreplace(_DIMENSIONS)).as_coeff_Mul()[1]
    names = {_MASS: sp.Symbol("kg"), _LENGTH: sp.Symbol("m"), _TIME: sp.Symbol("s")}
    return text(unit.xreplace(names))


# ---------------------------------------------------------------------------------------
# The engine
# ---------------------------------------------------------------------------------------
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
    coords = _heading_coordinates() if t.on_manifold else {}
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


# ---------------------------------------------------------------------------------------
# The transcriptions
# ---------------------------------------------------------------------------------------
def _equations_of_motion(s: ConstrainedSystem) -> list[Transcription]:
    """(1)–(5): the rows of M q̈ + H + Aᵀλ = Bτ, each with its multipliers."""
    lhs = s.mass_matrix * sp.Matrix(s.qddot) + s.bias + s.constraint_matrix.T * LAMBDA
    rhs = s.input_matrix * wmr.tau
    derived = [Form(_one(rhs[i]), _one(lhs[i])) for i in range(5)]
    out = []

    σ = _Slots()
    p1 = m * xdd + K * (thdd * SIN + thd**2 * COS) + σ("λ1 sin θ") * lam1 * SIN + σ(
        "cos θ(λ2 + λ3)"
    ) * COS * (lam2 + lam3)
    out.append(Transcription(
        "(1)", "m€xc + K(€u sin u + u_ 2 cos u)  l1 sin u  cos u(l2 + l3 ) = 0",
        Form(_one(sp.S.Zero), _one(p1)), derived[0], σ.done(),
    ))

    σ = _Slots()
    p2 = (
        m * ydd
        + σ("K(θ̈ cos θ …)") * K * (thdd * COS + σ("θ̇² sin θ") * thd**2 * SIN)
        + lam1 * COS
        + σ("sin θ(λ2 + λ3)") * SIN * (lam2 + lam3)
    )
    out.append(Transcription(
        "(2)", "m€yc  K(€u cos u  u_ 2 sin u) + l1 cos u  sin u(l2 + l3 ) = 0",
        Form(_one(sp.S.Zero), _one(p2)), derived[1], σ.done(),
    ))

    σ = _Slots()
    p3 = (
        I * thdd
        + K * (xdd * SIN + σ("ÿ cos θ") * ydd * COS)
        + σ("d λ1") * d * lam1
        + b / 2 * (lam3 + σ("λ2 in (λ3 λ2)") * lam2)
    )
    out.append(Transcription(
        "(3)", "I€u + K(€xc sin u  y€c cos u)  dl1 + b/2 (l3  l2 ) = 0",
        Form(_one(sp.S.Zero), _one(p3)), derived[2], σ.done(),
    ))

    out.append(Transcription(
        "(4)", "Iw €ur + l3 r = t r",
        Form(_one(tau_r), _one(I_w * thdd_r + lam3 * r)), derived[3],
        note="λ3 is printed where λ2 belongs: the right wheel rolls by (7), the second row of "
        "A, whose multiplier is λ2 (printed (9) with the printed A also gives r λ2); (5) "
        "correctly has λ3.",
    ))
    out.append(Transcription(
        "(5)", "Iw €ul + l3 r = t l",
        Form(_one(tau_l), _one(I_w * thdd_l + lam3 * r)), derived[4],
    ))
    return out


def _constraints(s: ConstrainedSystem) -> list[Transcription]:
    """(6)–(8): A q̇ = 0 row by row, and (13): θ̇ from (7) − (8)."""
    a_qdot = s.constraint_matrix * sp.Matrix(s.qdot)
    zero = _one(sp.S.Zero)
    out = []
    σ = _Slots()
    out.append(Transcription(
        "(6)", "y_ c cos u  x_ c sin u  ud_ = 0",
        Form(zero, _one(yd * COS + σ("ẋ sin θ") * xd * SIN + σ("θ̇ d") * thd * d)),
        Form(zero, _one(a_qdot[0])), σ.done(),
    ))
    σ = _Slots()
    out.append(Transcription(
        "(7)", "x_ c cos u + y_ c sin u + (b/2) u_  ru_ r = 0",
        Form(zero, _one(xd * COS + yd * SIN + b / 2 * thd + σ("r θ̇r") * r * thd_r)),
        Form(zero, _one(a_qdot[1])), σ.done(),
    ))
    σ = _Slots()
    out.append(Transcription(
        "(8)", "x_ c cos u + y_ c sin u  (b/2) u_  ru_ l = 0",
        Form(zero, _one(xd * COS + yd * SIN + σ("(b/2) θ̇") * b / 2 * thd
                        + σ("r θ̇l") * r * thd_l)),
        Form(zero, _one(a_qdot[2])), σ.done(),
    ))
    σ = _Slots()
    out.append(Transcription(
        "(13)", "u_ = r(u_ r  u_ l ) / b",
        Form(_one(r * (thd_r + σ("θ̇l") * thd_l) / b), _one(thd)),
        Form(_one(s.on_manifold[thd]), _one(thd)), σ.done(),
    ))
    return out


def _matrices_of_9(s: ConstrainedSystem) -> list[Transcription]:
    out = []
    σ = _Slots()
    mp = sp.Matrix([
        [m, 0, σ("M13 K sin θ") * K * SIN, 0, 0],
        [0, m, σ("M23 K cos θ") * K * COS, 0, 0],
        [σ("M31 K sin θ") * K * SIN, σ("M32 K cos θ") * K * COS, I, 0, 0],
        [0, 0, 0, I_w, 0],
        [0, 0, 0, 0, I_w],
    ])
    out.append(Transcription(
        "(9) M(q)", "m 0 K sin u 0 0 / 0 m K cos u 0 0 / K sin u K cos u I 0 0 / 0 0 0 Iw 0 / "
        "0 0 0 0 Iw",
        Form(mp, label="M(q)"), Form(s.mass_matrix, label="M(q)"), σ.done(),
    ))
    σ = _Slots()
    hp = _col(σ("H1 K θ̇² cos θ") * K * thd**2 * COS, σ("H2 K θ̇² sin θ") * K * thd**2 * SIN,
              0, 0, 0)
    out.append(Transcription(
        "(9) H(q,q̇)", "Ku_ 2 cos u / Ku_ 2 sin u / 0 / 0 / 0",
        Form(hp, label=r"H(q, \dot{q})"), Form(s.bias, label=r"H(q, \dot{q})"), σ.done(),
    ))
    bp = sp.Matrix([[0, 0], [0, 0], [0, 0], [1, 0], [0, 1]])
    out.append(Transcription(
        "(9) B", "0 0 / 0 0 / 0 0 / 1 0 / 0 1",
        Form(bp, label="B"), Form(s.input_matrix, label="B"),
    ))
    σ = _Slots()
    ap = sp.Matrix([
        [σ("A11 sin θ") * SIN, σ("A12 cos θ") * COS, σ("A13 d") * d, 0, 0],
        [σ("A21 cos θ") * COS, σ("A22 sin θ") * SIN, σ("A23 b/2") * b / 2, σ("A24 r") * r, 0],
        [σ("A31 cos θ") * COS, σ("A32 sin θ") * SIN, σ("A33 b/2") * b / 2, 0, σ("A35 r") * r],
    ])
    out.append(Transcription(
        "(9) A(q)", "sin u cos u d 0 0 / cos u sin u b/2 r 0 / cos u sin u b/2 0 r",
        Form(ap, label="A(q)"), Form(s.constraint_matrix, label="A(q)"), σ.done(),
        note="Note: the overall sign of a row of A is a convention that fixes the sign of its "
        "multiplier; (1)–(8) are checked against this A.",
    ))
    return out


def _multipliers(s: ConstrainedSystem) -> list[Transcription]:
    """(10)–(12): λ on the constraint manifold (the engine's λ(q, q̇, η̇))."""
    lam = s.multipliers_given_accelerations(wmr.tau)
    out = []
    σ = _Slots()
    p10 = (K * r + σ("m r d") * m * r * d) * (thdd_r + σ("θ̈l") * thdd_l) / b + m * r**2 * (
        thd_l**2 + σ("θ̇r²") * thd_r**2
    ) / (2 * b)
    out.append(Transcription(
        "(10)", "l1 = (Kr  mrd)(€ur  €ul)/b + mr2 (u_ 2l  u_ 2r)/2b",
        Form(_one(p10), label=r"\lambda_{1}"), Form(_one(lam[0]), label=r"\lambda_{1}"),
        σ.done(), on_manifold=True,
    ))

    σ = _Slots()
    p11 = (σ("Ω1") * Omega1 + thdd * (I + σ("K d") * K * d) + K * b * thd**2) / b
    o1 = (
        m * b * r * (thdd_r + thdd_l) / 2
        + (r * m * d**2 + σ("r K d in Ω1") * r * K * d) * (thdd_r + σ("θ̈l in Ω1") * thdd_l)
        / (2 * b)
        + σ("m b d θ̇²") * m * b * d * thd**2
        + r**2 * (thd_r**2 + σ("θ̇l² in Ω1") * thd_l**2) * (m * d + σ("K in (md K)") * K)
        / (4 * b)
    )
    out.append(Transcription(
        "(11)", "l2 = (O1 + u(I€  Kd) + Kbu_ 2)/b;  O1 = mbr(€ur + €ul)/2 + (rmd2  rKd)"
        "(€ur  €ul)/2b  mbdu_ 2 + r2 (u_ 2r  u_ 2l)(md  K)/4b",
        Form(_one(p11), label=r"\lambda_{2}", definitions=((Omega1, o1),)),
        Form(_one(lam[1]), label=r"\lambda_{2}"), σ.done(), on_manifold=True,
        note="Each of Ω1's four terms and the K b θ̇² term is 2 or ½ times the derived one "
        "(only θ̈(I − Kd) is right), so the printed λ2 does not satisfy (1)–(3) on the "
        "constraint manifold.",
    ))

    σ = _Slots()
    p12 = (σ("Ω2") * Omega2 + thdd * (K * d + σ("I") * I) + K * b * thd**2) / b
    o2 = (
        m * b * r * (thdd_r + thdd_l) / 4
        + (r * m * d**2 + σ("r K d in Ω2") * r * K * d) * (thdd_l + σ("θ̈r in Ω2") * thdd_r) / b
        + σ("m b² d θ̇²") * m * b**2 * d * thd**2
        + σ("r²(θ̇r² θ̇l²)(md K)/2b") * r**2 * (thd_r**2 + σ("θ̇l² in Ω2") * thd_l**2)
        * (m * d + σ("K in (md K)") * K) / (2 * b)
    )
    out.append(Transcription(
        "(12)", "l3 = (O2 + u(Kd€  I) + Kbu_ 2)/b;  O2 = mbr(€ur + €ul)/4 + (rmd2  rKd)"
        "(€ul  €ur)/b  mb2du_ 2  r2 (u_ 2r  u_ 2l)(md  K)/2b",
        Form(_one(p12), label=r"\lambda_{3}", definitions=((Omega2, o2),)),
        Form(_one(lam[2]), label=r"\lambda_{3}"), σ.done(), on_manifold=True,
        note="Ω2's m b² d θ̇² cannot be right (one length too many); the derivation has "
        "−m b d θ̇²/2 there, and K b θ̇²/2 instead of K b θ̇².",
    ))
    return out


def _reduced_form(s: ConstrainedSystem) -> list[Transcription]:
    """(14): M̃ q̈ + H̃ = u = Bτ."""
    out = []
    σ = _Slots()
    k_defs = (
        (k1, (m * d * r + σ("K r in k1") * K * r) / b * SIN + σ("m r/2 cos θ in k1")
         * m * r / 2 * COS),
        (k2, (K * r + σ("m d r in k2") * m * d * r) / b * SIN + σ("m r/2 cos θ in k2")
         * m * r / 2 * COS),
        (k3, (K * r + σ("m d r in k3") * m * d * r) / b * COS + σ("m r/2 sin θ in k3")
         * m * r / 2 * SIN),
        (k4, (m * d * r + σ("K r in k4") * K * r) / b * COS + σ("m r/2 sin θ in k4")
         * m * r / 2 * SIN),
        (k5, r * (I + σ("K d in k5") * K * d) / b),
    )
    mp = sp.Matrix([
        [m, 0, σ("M13 K sin θ") * K * SIN, k1, k2],
        [0, m, σ("M23 K cos θ") * K * COS, k3, k4],
        [σ("M31 K sin θ") * K * SIN, σ("M32 K cos θ") * K * COS, I, σ("M34 k5") * k5,
         σ("M35 k5") * k5],
        [σ("M41 k1") * k1, σ("M42 k3") * k3, σ("M43 k5") * k5, I_w, 0],
        [σ("M51 k2") * k2, σ("M52 k4") * k4, σ("M53 k5") * k5, 0, I_w],
    ])
    out.append(Transcription(
        "(14) M(q)", "m 0 K sin u k1 k2 / 0 m K cos u k3 k4 / K sin u K cos u I k5 k5 / "
        "k1 k3 k5 Iw 0 / k2 k4 k5 0 Iw; k1 = ((mdrKr)/b sin umr/2 cos u), k2 = ((Krmdr)/b "
        "sin umr/2 cos u), k3 = ((Krmdr)/b cos umr/2 sin u), k4 = ((mdrKr)/b cos umr/2 sin "
        "u), k5 = r(IKd)/b",
        Form(mp, label=r"\tilde{M}(q)", definitions=k_defs),
        Form(s.reduced_mass_matrix, label=r"\tilde{M}(q)"), σ.done(),
        note="Note: the signs that match make M̃ non-symmetric (M̃41 = −k1, M̃42 = −k3, "
        "M̃51 = −k2, M̃52 = −k4, M̃34 = M̃53 = −k5), as the derivation says it must be.",
    ))

    σ = _Slots()
    hp = _col(
        σ("H1 m d θ̇² cos θ") * m * d * thd**2 * COS
        + m * r**2 * SIN * (thd_r**2 + σ("θ̇l² in H1") * thd_l**2) / (2 * b),
        σ("H2 m d θ̇² sin θ") * m * d * thd**2 * SIN
        + σ("H2 m r² cos θ(…)") * m * r**2 * COS * (thd_r**2 + σ("θ̇l² in H2") * thd_l**2)
        / (2 * b),
        σ("H3 K r²(…)/2b") * K * r**2 * (thd_r**2 + σ("θ̇l² in H3") * thd_l**2) / (2 * b),
        σ("H4 K r θ̇²/2") * K * r * thd**2 / 2,
        σ("H5 K r θ̇²/2") * K * r * thd**2 / 2,
    )
    out.append(Transcription(
        "(14) H(q,q̇)", "mdu_ 2 cos u+mr2 sin u(u_ 2r  u_ 2l)/2b / mdu_ 2 sin umr2 cos u(u_ 2r  "
        "u_ 2l)/2b / Kr2 (u_ 2r  u_ 2l)/2b / Kru_ 2/2 / Kru_ 2/2",
        Form(hp, label=r"\tilde{H}(q, \dot{q})"),
        Form(s.reduced_bias, label=r"\tilde{H}(q, \dot{q})"), σ.done(), on_manifold=True,
    ))
    return out


def _kinematics(s: ConstrainedSystem) -> Transcription:
    """(31): the rows of S for ẋ, ẏ, θ̇."""
    σ = _Slots()
    sp_ = sp.Matrix([
        [σ("S11") * r / b * (b * COS + σ("d sin θ in S11") * d * SIN),
         σ("S12") * r / b * (b * COS + d * SIN)],
        [σ("S21") * r / b * (b * SIN + d * COS),
         σ("S22") * r / b * (b * SIN + σ("d cos θ in S22") * d * COS)],
        [σ("S31 r/b") * r / b, σ("S32 r/b") * r / b],
    ])
    derived = s.null_space.extract([0, 1, 2], [0, 1])
    return Transcription(
        "(31)", "(r/b)(b cos u  d sin u)  (r/b)(b cos u + d sin u) / (r/b)(b sin u + d cos u)  "
        "(r/b)(b sin u  d cos u) / (r/b)  (r/b)",
        Form(sp_, label="S_{1:3}(q)"), Form(derived, label="S_{1:3}(q)"), σ.done(),
        note="b is printed where b/2 belongs in the cos θ terms of row 1 and the sin θ terms "
        "of row 2: each wheel contributes half the axle's forward speed, r θ̇/2, by (7)–(8).",
    )


def _lumped(s: ConstrainedSystem) -> list[Transcription]:
    """m and I from the physical parameters (printed), K (not printed)."""
    rel = wmr.lumped_relations(wmr.physical_bodies())
    on_axle = {wmr.x_P: 0, wmr.y_P: 0}
    m_p, m_w, i_p, i_m = wmr.m_P, wmr.m_w, wmr.I_P, wmr.I_m
    out = [
        Transcription(
            "m relation", "m = mP + 2mw",
            Form(_one(m_p + 2 * m_w), label="m"), Form(_one(rel[m]), label="m"),
        ),
        Transcription(
            "I relation", "I = IP + mP d2 + 2mw ((b2/4) + d2) + 2Im",
            Form(_one(i_p + m_p * d**2 + 2 * m_w * (b**2 / 4 + d**2) + 2 * i_m), label="I"),
            Form(_one(rel[I].subs(on_axle)), label="I"),
            note="Note: derived for a platform centre of mass on the axle midpoint "
            f"(x_P = y_P = 0); in general I = `{text(rel[I])}`.",
        ),
    ]
    out.append(Transcription(
        "K relation", "expression of K is given in Nandy et al.; K = 0.34 kg m",
        None, Form(_one(rel[K]), label="K"), reconstruction=_k_reconstruction(rel),
        printed_display=rf"K = {PRINTED_PARAMETERS['K']:g}\ \mathrm{{kg\,m}}"
        r"\quad\text{(value only; the relation is not printed)}",
    ))
    return out


def _k_reconstruction(rel: dict[sp.Symbol, sp.Expr]) -> str:
    """What the K entry rebuilds, and how the printed numbers compare with it."""
    p = PRINTED_PARAMETERS
    k_general = rel[K]
    k_axle = sp.factor(k_general.subs({wmr.x_P: 0}))  # = m d with m = m_P + 2 m_w
    k_axle_m = sp.simplify(k_axle.subs(wmr.m_P, m - 2 * wmr.m_w))
    value_axle = float(k_axle_m.subs({m: p["m"], d: p["d"]}))
    offset_mm = 1000 * p["K"] / p["m"]
    # (d − x_P)² = d² also for x_P = 2d: the platform's centre of mass d ahead of C.
    k_ahead = sp.expand(k_general.subs({wmr.x_P: 2 * d}))
    m_w_needed = sp.solve(
        sp.Eq(k_ahead.subs(wmr.m_P, m - 2 * wmr.m_w), K), wmr.m_w
    )[0].subs({m: p["m"], d: p["d"], K: p["K"]})
    return (
        f"Not printed (\"given in Nandy et al.\"); rebuilt from the kinetic energy as the "
        f"first moment of mass behind C: K = `{text(k_general)}` (x_P = platform centre of "
        f"mass ahead of the axle midpoint). The printed I relation's m_P d² term is the case "
        f"x_P = y_P = 0, for which K = `{text(k_axle_m)}` = {value_axle:.2f} kg m with the "
        f"printed m = {p['m']:g} kg, d = {p['d']:g} m; the paper prints K = {p['K']:g} kg m, "
        f"i.e. a centre of mass {offset_mm:.1f} mm behind C (and the text calls C the centre "
        f"of mass, which would make K = 0). The other reading of m_P d², x_P = 2d, gives "
        f"K = `{text(k_ahead)}`, which is 0.34 kg m only with m_w = {float(m_w_needed):.1f} kg "
        f"per wheel of the {p['m']:g} kg. The printed numbers are inconsistent with the printed I "
        f"relation; the model keeps K a parameter and uses the printed value."
    )


def transcriptions() -> list[Transcription]:
    """Every printed equation of the dynamics, in the paper's order."""
    s = wmr.wmr_system()
    eom = _equations_of_motion(s)
    cons = _constraints(s)
    return [
        *eom,
        *cons[:3],
        *_matrices_of_9(s),
        *_multipliers(s),
        cons[3],
        *_reduced_form(s),
        _kinematics(s),
        *_lumped(s),
    ]


@functools.cache
def _judgements() -> tuple[Judgement, ...]:
    return tuple(judge(t) for t in transcriptions())


def judgements() -> list[Judgement]:
    """The verdicts with the data behind them (cached: the derivation runs once)."""
    return list(_judgements())


def verdicts() -> list[Verdict]:
    """One verdict per printed equation (or printed matrix of an equation)."""
    return [j.as_verdict() for j in _judgements()]


def verdict_table(items: Iterable[Verdict] | None = None) -> dict[str, VerdictKind]:
    """equation → verdict."""
    return {v.equation: v.verdict for v in (verdicts() if items is None else items)}
