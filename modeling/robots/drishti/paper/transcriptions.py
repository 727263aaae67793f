"""The paper's printed equations as read, and the derived forms they are compared with.

Every printed sign that is visible (a ``+``, an ``=``) is kept. Wherever the extraction
shows no operator between two terms, or a matrix entry could have carried a leading minus,
the transcription multiplies by a *sign slot* ``σ_k ∈ {+1, −1}`` (a ``sympy.Symbol`` named
``sigma_k``). Diagonal inertias (m, I, I_w) and the 0/1 entries of B are read as printed.
Auxiliary printed definitions (Ω1, Ω2 of (11)–(12), k1…k5 of (14)) are kept as symbols in
the display and substituted before comparing. Each :class:`Transcription` also records the
extracted text it was read from, the derived form (from the engine, never typed here), and
for an erratum a one-line explanation; :mod:`.signs` judges it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import sympy as sp

from modeling.lagrange import ConstrainedSystem
from modeling.robots.drishti import model as wmr
from modeling.robots.drishti.paper.display import LATEX_NAMES, text
from modeling.robots.drishti.paper.symbols import (
    COS,
    LAMBDA,
    SIN,
    I,
    I_w,
    K,
    Omega1,
    Omega2,
    b,
    d,
    k1,
    k2,
    k3,
    k4,
    k5,
    lam1,
    lam2,
    lam3,
    m,
    r,
    tau_l,
    tau_r,
    thd,
    thd_l,
    thd_r,
    thdd,
    thdd_l,
    thdd_r,
    xd,
    xdd,
    yd,
    ydd,
)

# The numbers the paper prints for Drishti (Section "Experimental results").
PRINTED_PARAMETERS: dict[str, float] = {
    "m": 36.0, "d": 0.12, "r": 0.096, "b": 0.414, "I": 5.72, "Iw": 0.07, "K": 0.34,
}



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

