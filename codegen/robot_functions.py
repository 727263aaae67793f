"""A robot's generated functions: the symbolic model and control laws of ``modeling``
wrapped as FunctionSpecs with named, documented inputs and outputs, for any
``modeling.robot_model.RobotModel`` (n coordinates, m driven wheels).

Modules (one C ``.h``/``.c`` pair, one Python module, one set of CasADi functions each;
``<prefix>`` is the robot's, ``wmr`` for the paper's robot):

* ``<prefix>_model``: M and H of (14), forward dynamics, kinematics (31), the minimal form
  and the linearisation of the state equation x = (q, η), η the driven wheels' rates; in
  C also the forward dynamics' prepare-parameters API (``<prefix>_model_prepare``,
  ``<prefix>_forward_dynamics_prepared``).
* ``<prefix>_laws``: the controllers' pure kernels — the time-delay estimate (17), the
  TDROC gain (25), each registered controller's law (``modeling.controllers.REGISTRY``),
  P of the Lyapunov equation — for each formulation.
  The controller step functions (``wmr_tdroc_step`` …) are templates around these that
  own validation, history and status; they do no arithmetic of their own beyond copying.
* ``<prefix>_plant``: the simulated robot's state derivative and the payload relations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cache

import sympy as sp

from codegen.contact_forces import (
    ContactForms,
    contact_force_forms,
    contact_rows,
    root_frame_contact_forms,
)
from codegen.controller_layout import row_span, words
from codegen.cse import cse_function
from codegen.prepare import prepared_form
from codegen.spec import Argument, Field, FunctionSpec, Guard
from modeling import controllers as ctl
from modeling.description.derive import cofactor_determinant
from modeling.lagrange import ConstrainedSystem, StagedMinimal
from modeling.robot_model import Parameter, RobotModel
from modeling.staged import Stage, definitions_read
from modeling.trig_polynomial import trig_polynomial

MAX_WINDOW = 8  # TDROC's largest n (compile-time history size)



def status(model: RobotModel, name: str) -> str:
    """A status code's C name for ``model``: ``WMR_ERR_BAD_PARAMS`` for prefix ``wmr``."""
    return f"{model.prefix.upper()}_{name}"



def _fields(params: tuple[Parameter, ...]) -> tuple[Field, ...]:
    return tuple(Field(p.key, (p.symbol,), doc=p.comment, c_name=p.c_name) for p in params)


def params_arg(
    model: RobotModel, name: str = "p", doc: str = "lumped robot parameters"
) -> Argument:
    return Argument(name, "params", fields=_fields(model.params), doc=doc)


def array(
    name: str,
    symbols: sp.Matrix | tuple[sp.Symbol, ...],
    doc: str = "",
    shape: tuple[int, int] | None = None,
) -> Argument:
    syms = tuple(symbols)
    return Argument(name, "array", shape=shape or (len(syms), 1), symbols=syms, doc=doc)


def out(
    name: str, exprs: sp.Matrix | list[sp.Expr], doc: str = "", shape: tuple[int, int] | None = None
) -> Argument:
    if isinstance(exprs, sp.MatrixBase):
        shape = shape or exprs.shape
        values = tuple(exprs)  # row-major
    else:
        values = tuple(exprs)
        shape = shape or (len(values), 1)
    return Argument(name, "array", shape=shape, exprs=values, doc=doc)


def leading_minors(mbar: sp.Matrix) -> list[sp.Expr]:
    def minor(k: int) -> sp.Expr:
        if k == 2:  # written out: the form CSE already shares with the 2x2 solve
            return mbar[0, 0] * mbar[1, 1] - mbar[0, 1] * mbar[1, 0]
        return cofactor_determinant(mbar.extract(list(range(k)), list(range(k))))

    return [minor(k) for k in range(1, mbar.rows + 1)]


def minor_doc(k: int, n: int) -> str:
    if k == 1:
        return "(S^T M S)[0][0] > 0"
    if k == n:
        return "det(S^T M S) > 0: a positive-definite model"
    return f"leading {k}x{k} minor of S^T M S > 0"


def guard_mass_matrix(model: RobotModel) -> sp.Matrix:
    """SᵀMS as the parameter guards read it: the same grouped entries as the forward
    dynamics, so CSE shares them. Its leading minors must be positive (Sylvester)."""
    return model.system.minimal_mass_matrix.applyfunc(model.evaluation_form)


def positive_parameters(model: RobotModel) -> list[tuple[sp.Symbol, str]]:
    """(symbol, doc) of each parameter the guards require positive."""
    by_key = {p.key: p.symbol for p in model.params}
    return [(by_key[k], f"{k} > 0") for k in model.positive]


@cache
def _param_guards(model: RobotModel) -> tuple[Guard, ...]:
    bad = status(model, "ERR_BAD_PARAMS")
    positive = [Guard(bad, symbol, doc) for symbol, doc in positive_parameters(model)]
    # Sylvester: all leading minors of S^T M S positive <=> positive definite.
    mbar = (staged_forms(model).solved_mbar if model.staged
            else guard_mass_matrix(model))
    minors = leading_minors(mbar)
    return (
        *positive,
        *(Guard(bad, m, minor_doc(k + 1, len(minors)))
          for k, m in enumerate(minors)),
    )


def forward_dynamics_forms(
    model: RobotModel, system: ConstrainedSystem | None = None
) -> tuple[sp.Matrix, sp.Matrix]:
    """(η̇, q̈) in evaluation form: the grouped 2×2 solve when there are two driven wheels
    (``ConstrainedSystem.compact_forward_dynamics``), else adj(M̄)/det(M̄) left unexpanded;
    q̈'s position rows rotated once from the body frame (``_rotated_plane_rows``)."""
    s = model.system if system is None else system
    tau = model.tau
    if model.nu == 2:
        eta_dot, qdd = s.compact_forward_dynamics(tau, model.evaluation_form)
    else:
        eta_dot = s.minimal_forward_dynamics(tau)
        qdd = s.null_space * eta_dot + s.null_space_rate
    return eta_dot, _rotated_plane_rows(model, s, eta_dot, qdd)


def _rotated_plane_rows(
    model: RobotModel, s: ConstrainedSystem, eta_dot: sp.Matrix, qdd: sp.Matrix
) -> sp.Matrix:
    """``qdd`` with its two position rows (ẍ, ÿ) of q̈ = S η̇ + Ṡ η (9), (31) written as
    R(θ) a: a = R(θ)ᵀ(S η̇ + Ṡ η) in the body frame, free of the heading θ, computed once
    and rotated once (cos θ and sin θ applied to two values; the expanded rows repeat
    them in every product). ``qdd`` unchanged when the robot has no such pair of rows
    (rows that depend on θ whose body-frame form does not)."""
    heading = model.heading
    rows = [i for i in range(len(model.q))
            if i not in model.actuated and model.q[i] != heading
            and (s.null_space.row(i).has(heading) or s.null_space_rate[i].has(heading))]
    if len(rows) != 2:
        return qdd
    i, j = rows
    c, sn = sp.cos(heading), sp.sin(heading)
    e = sp.symbols(f"_eta_dot0:{len(eta_dot)}")  # η̇ held as symbols while factoring
    body = []
    for along, across in ((c, sn), (-sn, c)):  # rows of R(θ)ᵀ
        s_row = (along * s.null_space.row(i) + across * s.null_space.row(j)).applyfunc(
            sp.trigsimp)
        rate = sp.trigsimp(along * s.null_space_rate[i] + across * s.null_space_rate[j])
        if s_row.has(heading) or rate.has(heading):
            return qdd
        # factored per row (r(η̇_r + η̇_l)/2, d r(η̇_r − η̇_l)/b for Drishti): the factors
        # CSE shares with θ̈'s row
        body.append(sp.factor((s_row * sp.Matrix(e))[0]).xreplace(dict(zip(e, eta_dot,
                                                                             strict=True)))
                    + sp.factor(rate))
    a0, a1 = body
    out = sp.Matrix(qdd)
    out[i] = c * a0 - sn * a1
    out[j] = sn * a0 + c * a1
    return out


@dataclass(frozen=True)
class StagedForms:
    """A staged robot's model functions (``RobotModel.staged``): the minimal form, the
    forward dynamics and the state equation's Jacobians as quantities of one stage."""

    stage: Stage
    mbar: sp.Matrix
    hbar: sp.Matrix
    eta_dot: sp.Matrix
    qdd: sp.Matrix
    xdot: sp.Matrix
    jac_x: sp.Matrix
    jac_u: sp.Matrix
    # the mass matrix the solve factors (M̄, or M̄_u in the root's twist): positive
    # definite exactly when M̄ is, and what the guards' leading minors read
    solved_mbar: sp.Matrix
    minimal: StagedMinimal  # the minimal form these are of (the contact forces read it)

    def with_definitions(self, spec: FunctionSpec) -> FunctionSpec:
        """``spec`` with the quantities its outputs and guards read."""
        exprs = [e for a in spec.outputs for e in a.exprs] + [g.condition for g in spec.guards]
        return replace(spec, definitions=self.stage.definitions_for(exprs))

    def depends_on(self, exprs: sp.Matrix, symbols: tuple[sp.Symbol, ...]) -> bool:
        """Whether ``exprs`` depend on ``symbols``, through the quantities they read."""
        wanted = set(symbols)
        defs = self.stage.definitions_for(list(exprs))
        return any(e.free_symbols & wanted for e in [*exprs, *(d for _, d in defs)])


@cache
def staged_forms(model: RobotModel, plant: bool = False) -> StagedForms:
    """The model functions (the plant's with ``plant``) staged: M̄, H̄ and Sᵀ B from S, M
    and H entry by entry, η̇ from a solve in the stage, the Jacobians by differentiating
    through the quantities (``modeling.staged``)."""
    system = model.plant_system if plant else model.system
    stage = Stage("_ps" if plant else "_ms")
    # In the root body's frame (the same functions of q, with the hitch angles' sin and
    # cos only; q̇'s and q̈'s x, y rows rotated back once): so are their Jacobians.
    sm = system.staged_minimal(stage, root_frame=True, positive=model.positive_symbols)
    eta_dot, qdd = sm.forward_dynamics(model.tau)
    x = [*model.q, *system.eta]
    xdot = sp.Matrix([*sm.world_velocities(), *eta_dot])
    jac_x = sp.Matrix(len(xdot), len(x), lambda i, j: stage.derivative(xdot[i], x[j]))
    jac_u = sp.Matrix(len(xdot), model.nu, lambda i, j: stage.derivative(xdot[i],
                                                                          model.tau[j]))
    return StagedForms(stage, sm.mass_matrix, sm.bias, eta_dot, qdd, xdot, jac_x, jac_u,
                       sm.solved_mass_matrix, sm)


@cache
def model_contact_forms(model: RobotModel) -> ContactForms:
    """The contact forces of ``model``: for a staged robot whose model functions are the
    root frame's, through their stage (``root_frame_contact_forms``: S, M̄, H̄ and the
    solve are theirs, shared with them), else through a stage of their own."""
    if model.staged and model.system.planar_frame:
        forms = staged_forms(model)  # complete first: its quantities keep their numbers
        if forms.minimal.plane is not None:
            return root_frame_contact_forms(model, forms.minimal)
    return contact_force_forms(model)


@cache
def model_specs(model: RobotModel) -> tuple[FunctionSpec, ...]:
    """``<prefix>_model``: the functions the C API of issue 3 names."""
    s = model.system
    n, m = model.nq, model.nu
    names = model.coordinate_names
    q = array("q", model.q, ", ".join(names))
    qdot = array("qdot", model.qdot, "generalised velocities")
    eta = tuple(model.qdot[i] for i in model.actuated)
    wheel_rates = array(
        "wheel_rates", eta, ", ".join(f"{names[i]} rate" for i in model.actuated)
    )
    tau = array("tau", model.tau, "wheel torques " + ", ".join(model.input_names))
    p = params_arg(model)
    staged = staged_forms(model) if model.staged else None
    if staged is not None:
        eta_dot, qdd, mbar, hbar = staged.eta_dot, staged.qdd, staged.mbar, staged.hbar
        jac_x, jac_u = staged.jac_x, staged.jac_u
        mbar_on_q = staged.depends_on(mbar, model.q)
        pose_rates = staged.xdot[:n, 0]
    else:
        # Evaluation forms (equal to reduced_/minimal_forward_dynamics; tests check it).
        eta_dot, qdd = forward_dynamics_forms(model)
        # State x = (q, η): ẋ = (S(q) η, η̇(q, η, τ)); its Jacobians linearise the robot.
        x = sp.Matrix([*model.q, *eta])
        xdot = sp.Matrix([*(s.null_space * sp.Matrix(eta)), *eta_dot])
        jac_x = xdot.jacobian(x)
        jac_u = xdot.jacobian(model.tau)
        mbar, hbar = s.minimal_mass_matrix, s.minimal_bias
        mbar_on_q = _depends_on_q(mbar, model)
        pose_rates = s.null_space * sp.Matrix(eta)
    guards = _param_guards(model)
    dependent = [i for i in range(n) if i not in model.actuated]
    dep_names = ", ".join(names[i] for i in dependent)
    rate_list = ", ".join(f"qdot[{i}]" for i in model.actuated)
    state_doc = ", ".join(f"{names[i]} rate" for i in model.actuated)

    def checked(spec: FunctionSpec) -> FunctionSpec:
        return replace(
            spec,
            returns_status=True,
            guards=guards,
            nonfinite_input=status(model, "ERR_NONFINITE_INPUT"),
            nonfinite_output=status(model, "ERR_NONFINITE_OUTPUT"),
        )

    paper_specs = (
        FunctionSpec(
            "mass_matrix",
            "M(q) of (14), the reduced (multiplier-free) mass matrix; not symmetric.",
            (p, q),
            (out("M", s.reduced_mass_matrix, f"{n}x{n} row-major"),),
            ("(14)",),
        ),
        FunctionSpec(
            "bias_forces",
            f"H(q, qdot) of (14). Rows {row_span(dependent)} hold the velocity-product terms "
            "of the twice\n"
            "differentiated constraints; valid for qdot on the constraint manifold.",
            (p, q, qdot),
            (out("H", s.reduced_bias),),
            ("(14)",),
        ),
    ) if model.paper else ()
    specs = (
        *paper_specs,
        replace(checked(
            FunctionSpec(
                "forward_dynamics",
                "qddot solving (14) with u = B tau, by structured elimination:\n"
                "eta_dot = (S^T M S)^-1 (tau - S^T(M Sdot eta + H)),\n"
                "qddot = S eta_dot + Sdot eta.\n"
                f"Only the wheel rates {rate_list} are read: the other velocities follow\n"
                "from the constraints (6)-(8).",
                (p, q, qdot, tau),
                (out("qddot", qdd),),
                ("(9)", "(14)", "(31)"),
            )
        ), prepared=True,  # <prefix>_model_prepare + <prefix>_forward_dynamics_prepared
            calls_prepared=staged is not None),  # a staged robot's: once in its C module
        FunctionSpec(
            "kinematics",
            f"(31): pose rates ({dep_names}) from the wheel rates, xi_dot = S_d(q) eta.",
            (p, q, wheel_rates),
            (out("pose_rates", sp.Matrix([pose_rates[i] for i in dependent])),),
            ("(31)", "(13)"),
        ),
        FunctionSpec(
            "minimal_mass_matrix",
            f"Mbar = S^T M S of the minimal {words(m)}-coordinate model"
            + (" (constant for K_lat = 0)." if not mbar_on_q else " (depends on q)."),
            (p, q),
            (out("M", mbar, f"{m}x{m} row-major"),),
            ("(9)",),
        ),
        FunctionSpec(
            "minimal_bias_forces",
            "Hbar = S^T (M Sdot eta + H) of the minimal model.",
            (p, q, wheel_rates),
            (out("H", hbar),),
            ("(9)",),
        ),
        checked(
            FunctionSpec(
                "minimal_forward_dynamics",
                "Wheel accelerations of the minimal model: Mbar eta_dot + Hbar = tau.",
                (p, q, wheel_rates, tau),
                (out("wheel_accels", eta_dot),),
                ("(9)",),
            )
        ),
        FunctionSpec(
            "linearization",
            _wrap(f"Jacobians of the state equation x_dot = f(x, tau), x = (q, {state_doc}), "
                  f"f = (S(q) eta, eta_dot): A = df/dx ({n + m}x{n + m}), "
                  f"B = df/dtau ({n + m}x{m})."),
            (p, q, wheel_rates, tau),
            (out("A", jac_x, f"{n + m}x{n + m} row-major"),
             out("B", jac_u, f"{n + m}x{m} row-major")),
            ("(9)", "(31)"),
        ),
    )
    specs = specs if staged is None else tuple(_sharing(staged.with_definitions(f))
                                               for f in specs)
    net_tau = replace(tau, doc="net wheel torques (after bearing friction) "
                      + ", ".join(model.input_names))
    contact = checked(FunctionSpec("wheel_contact_forces", "", (p, q, wheel_rates, net_tau), ()))
    contact_spec = _contact_forces_spec(model, contact)
    if staged is not None and model_contact_forms(model).stage is staged.stage:
        contact_spec = _sharing(contact_spec)
    return (*specs, contact_spec, *_traction_specs(model, contact))


# The model functions of a staged robot that read S(q), M̄ and H̄ from one helper
# (``codegen.shared``): printed once per module instead of once per function.
STAGED_SHARES = "staged_quantities"
_SHARING = ("minimal_bias_forces", "minimal_forward_dynamics", "linearization",
            "wheel_contact_forces")


def _sharing(spec: FunctionSpec) -> FunctionSpec:
    return replace(spec, shares=STAGED_SHARES) if spec.name in _SHARING else spec


def _contact_forces_spec(model: RobotModel, base: FunctionSpec) -> FunctionSpec:
    """``wheel_contact_forces``: the ground's force on each wheel from the multipliers of
    (9) (``codegen.contact_forces``), with ``base``'s inputs and status contract. Its
    definitions: its own stage's, then those its guards read (a staged robot's M̄)."""
    forms = model_contact_forms(model)
    rows = contact_rows(model)
    axles = "; ".join(f"lateral[{k}]: " + ", ".join(f"'{w}'" for w in ws)
                      for k, ws in enumerate(rows.lateral_wheels))
    doc = (
        "Contact forces from the multipliers of (9), M qddot + H = B tau - A^T lambda:\n"
        "A_d^T lambda = (B tau - H - M qddot)_d with qddot from the minimal forward\n"
        "dynamics (the route of (10)-(12)). longitudinal[k] (N): the ground's force on\n"
        "driven wheel " + ", ".join(f"'{w}'" for w in rows.driven)
        + " along its heading (positive forward;\n"
        "(tau - I_w thetaddot)/r). lateral[k] (N): the ground's force along the axle,\n"
        "positive to the wheel's left, of one no-side-slip row: an axle's wheels share\n"
        "one row (their split is statically indeterminate).\n"
        + _wrap(axles + ".") + "\nValid on the constraint manifold (the wheels roll)."
    )
    outputs = (out("longitudinal", forms.longitudinal, "N, per driven wheel"),
               out("lateral", forms.lateral, "N, per no-side-slip row (axle)"))
    exprs = [*forms.longitudinal, *forms.lateral]
    guards = [g.condition for g in base.guards]
    if model.staged and forms.stage is staged_forms(model).stage:  # one stage: one list
        definitions = forms.stage.definitions_for([*exprs, *guards])
    else:
        guard_defs = (staged_forms(model).stage.definitions_for(guards)
                      if model.staged else ())
        definitions = (*forms.stage.definitions_for(exprs), *guard_defs)
    return replace(base, doc=doc, outputs=outputs, equations=("(9)", "(10)-(12)"),
                   definitions=definitions)


# The friction budget mu N_k a traction function accepts (N): normal in float32 and in
# double, so its margins are finite and signed right for every finite force (issue 52).
FRICTION_MIN, FRICTION_MAX = 1e-30, 1e30


def _traction_specs(model: RobotModel, base: FunctionSpec) -> tuple[FunctionSpec, ...]:
    """``traction_margins`` and ``traction_check``: each driven wheel's traction margin
    mu N_w - sqrt(F_x^2 + (s_w F_y)^2) on a friction circle, from the contact forces of (9)
    that ``wheel_contact_forces`` wrote (F_y its axle's lateral force, s_w the wheel's share
    of it: the slip monitor's static-load split, ``runtime.sim.slip_monitor``). The check
    returns ``<P>_WARN_TRACTION`` (> 0, not an error) where a margin is not positive.

    They take the forces, not the state: the firmware has them from the one call of
    ``wheel_contact_forces`` after its step, and the multipliers' elimination (the bulk of
    that function, tens of kB of C for a two-trailer train) is written once."""
    rows = contact_rows(model)
    m, k = model.nu, len(rows.lateral_wheels)
    row_of = []
    for w in rows.driven:
        holding = [j for j, ws in enumerate(rows.lateral_wheels) if w in ws]
        if len(holding) != 1:
            raise ValueError(f"robot '{model.name}': driven wheel '{w}' is in "
                             f"{len(holding)} no-side-slip rows (one expected)")
        row_of.append(holding[0])
    fx = sp.symbols(f"force_x0:{m}", real=True)
    fy = sp.symbols(f"force_y0:{k}", real=True)
    mu = sp.Symbol("mu_floor", positive=True)
    loads = sp.symbols(f"load_w0:{m}", positive=True)
    shares = sp.symbols(f"share_w0:{m}", real=True)
    # Each wheel's share of its axle's lateral force, a quantity of its own so that the
    # root is printed as the backends' 2-norm (C: <prefix>_norm2, scaled beyond the range
    # where the squares overflow or underflow): squaring Fy before the share overflowed
    # float32 above 1.8e19 N and underflowed below 1e-19 N (issue 52).
    lateral_share = sp.symbols(f"lateral_w0:{m}", real=True)
    definitions = tuple((lateral_share[i], shares[i] * fy[row_of[i]]) for i in range(m))
    margins = [mu * loads[i] - sp.sqrt(fx[i] ** 2 + lateral_share[i] ** 2) for i in range(m)]
    wheels = ", ".join(f"'{w}'" for w in rows.driven)
    inputs = (array("longitudinal", fx, "N, per driven wheel (wheel_contact_forces)"),
              array("lateral", fy, "N, per no-side-slip row (wheel_contact_forces)"),
              array("mu", (mu,), "the floor's friction coefficient"),
              array("loads", loads, f"N_w (N), static normal load of driven wheel {wheels}"),
              array("shares", shares, "each driven wheel's share of its axle's lateral force "
                    "(the slip monitor's: N_w / sum of its axle's N)"))
    bad = status(model, "ERR_BAD_TRACTION")

    def within(x: sp.Expr, lo: float, hi: float) -> sp.Expr:
        return sp.Piecewise((sp.S.One, sp.And(x >= lo, x <= hi)), (sp.S.Zero, True))

    # The range where every margin the function returns is finite when the true one is, with
    # its sign (a normal mu N_k far from both ends of float32's range; |share Fy| <= |Fy|).
    guards = (Guard(bad, mu, "mu > 0"),
              *(Guard(bad, n, f"loads[{i}] > 0") for i, n in enumerate(loads)),
              *(Guard(bad, within(mu * n, FRICTION_MIN, FRICTION_MAX),
                      f"mu loads[{i}] in [{FRICTION_MIN:g}, {FRICTION_MAX:g}] N")
                for i, n in enumerate(loads)),
              *(Guard(bad, within(s, 0.0, 1.0), f"shares[{i}] in [0, 1]")
                for i, s in enumerate(shares)))
    doc = ("Traction margins on a friction circle: margins[k] = mu N_k - sqrt(Fx_k^2 +\n"
           "(share_k Fy_axle)^2) (N) of driven wheel " + wheels + ", Fx, Fy the contact\n"
           "forces wheel_contact_forces wrote (the multipliers of (9)). Negative: the wheel\n"
           "needs more traction than the floor gives and slips. The root is a scaled 2-norm:\n"
           "a margin is finite whenever the true one is, with its sign, for every finite\n"
           f"force (mu N_k in [{FRICTION_MIN:g}, {FRICTION_MAX:g}] N, shares in [0, 1]: else "
           "ERR_BAD_TRACTION).")
    margin_spec = replace(
        base, name="traction_margins", doc=doc, inputs=inputs,
        outputs=(out("margins", margins, "N, per driven wheel"),),
        equations=("(9)", "(10)-(12)"), guards=guards, definitions=definitions, prepared=False)
    warn = status(model, "WARN_TRACTION")
    check = replace(
        margin_spec, name="traction_check",
        doc=doc + "\nA check for firmware after the controller step: returns " + warn
        + " (> 0, not\nan error) when a margin is <= 0, then, as on any status but OK, "
        "writes nothing\n(traction_margins gives the margins whatever their sign).",
        guards=(*guards, *(Guard(warn, e, f"wheel '{w}' keeps grip: margin > 0")
                           for e, w in zip(margins, rows.driven, strict=True))))
    return margin_spec, check


def _wrap(text: str, width: int = 79) -> str:
    """Break a doc string into lines of at most ``width`` characters (word boundaries)."""
    lines: list[str] = []
    for word in text.split(" "):
        if lines and len(lines[-1]) + 1 + len(word) <= width:
            lines[-1] += " " + word
        else:
            lines.append(word)
    return "\n".join(lines)


def _depends_on_q(matrix: sp.Matrix, model: RobotModel) -> bool:
    return bool(matrix.free_symbols & set(model.q))


def _nominal(model: RobotModel, doc: str = "nominal parameters of M-hat") -> Argument:
    return params_arg(model, "p", doc)


def _minv_norm_spec(model: RobotModel, f: ctl.Formulation) -> FunctionSpec:
    norm = ctl.mass_inverse_norm(f, model)
    cm = ctl.control_model(f, model)
    if cm.depends_on([norm], model.q):
        return FunctionSpec(
            f"{f}_minv_norm",
            f"({f} formulation) ||Mhat(q)^-1||_F of (25). Mhat depends on the hitch angles,\n"
            "so the norm is evaluated at the measured q in every step.",
            (_nominal(model), array("q", model.q, "measured q")),
            (out("norm", [norm]),),
            ("(25)",),
            definitions=cm.definitions([norm]),
        )
    return FunctionSpec(
        f"{f}_minv_norm",
        f"({f} formulation) ||Mhat^-1||_F of (25). Mhat(theta) = T Mhat(0) T^T with T\n"
        "an orthogonal heading rotation, so the norm depends on the parameters only.",
        (_nominal(model),),
        (out("norm", [norm]),),
        ("(25)",),
    )


@cache
def mhat_kernels(model: RobotModel, formulation: ctl.Formulation) -> bool:
    """Whether the steps of ``formulation`` take M̂(q)'s entries as an input (the
    ``_mhat`` kernels): a staged control model whose M̂ depends on q (a robot with a
    trailer: M̂ on the hitch angles). The step evaluates M̂(q) once (``<f>_mhat``), passes it
    to ‖M̂⁻¹‖ of (25) and the law, and keeps it for the next step's (17), which needs
    M̂(q(t − h)): one evaluation a step where the kernels of q made three."""
    if formulation not in model.formulations:
        return False
    cm = ctl.control_model(formulation, model)
    return cm.stage is not None and cm.depends_on(list(cm.mass), model.q)


# The trigonometric-polynomial M-hat is taken only if its code (the coefficients _init keeps,
# and the step's part) is at most this many times the staged form's: one trailer 160 ops
# against 100 (the step's part 77 -> 17), two trailers 697 against 193 (168 -> 105 a step
# for 2.4 kB more of Cortex-M4 code): near-linear code growth with the bodies first.
POLYNOMIAL_CODE_GROWTH_MAX = 2


def _mhat_spec(model: RobotModel, f: ctl.Formulation) -> FunctionSpec:
    """``<f>_mhat``: M̂(q), k×k row-major, the nominal model's mass matrix: the staged
    quantities, or M̂'s entries as trigonometric polynomials of the hitch angles
    (:mod:`modeling.trig_polynomial`: the coefficients kept by ``_init``, a step evaluates
    the monomials and a multiply-add per coefficient) when a step evaluates that in fewer
    operations and its code stays within :data:`POLYNOMIAL_CODE_GROWTH_MAX` of the staged
    form's (one trailer: the polynomial; two and three: the staged form)."""
    cm = ctl.control_model(f, model)
    k = cm.mass.rows
    staged = FunctionSpec(
        f"{f}_mhat",
        f"({f} formulation) Mhat(q), the nominal mass matrix the laws and (17) use. A step\n"
        "evaluates it once, for ||Mhat^-1|| (25) and the law, and keeps it for the next\n"
        "step's (17), which needs Mhat(q(t-h)).",
        (_nominal(model), array("q", model.q, "measured q")),
        (out("M", list(cm.mass), f"{k}x{k} row-major"),),
        ("(9)",),
        definitions=cm.definitions(list(cm.mass)),
    )
    step_ops, kept_ops = _split_ops(staged)
    # a polynomial with more monomials than the staged step has operations cannot win
    polynomial = trig_polynomial(list(cm.mass), model.q, staged.definitions, step_ops)
    if polynomial is None:
        return staged
    candidate = replace(
        staged, outputs=(out("M", polynomial, f"{k}x{k} row-major"),), definitions=(),
        doc=staged.doc + "\nEach entry a polynomial in sin and cos of the hitch angles, its\n"
        "coefficients of the parameters only (a step's _init keeps them).")
    poly_step, poly_kept = _split_ops(candidate)
    if (poly_step < step_ops
            and poly_step + poly_kept <= POLYNOMIAL_CODE_GROWTH_MAX * (step_ops + kept_ops)):
        return candidate
    return staged


def _split_ops(spec: FunctionSpec) -> tuple[int, int]:
    """The operations of ``spec`` (a kernel of the parameters and q) a step spends, and
    those ``_init`` spends on the parameter-only subexpressions it keeps
    (:mod:`codegen.prepare`)."""
    form = prepared_form(cse_function(spec, reciprocals=True),
                         replace(spec, returns_status=True))
    return form.ops("per_call").arithmetic, form.ops("prepare").arithmetic


def _mhat_variant(spec: FunctionSpec, coords: tuple[sp.Symbol, ...], mass: list[sp.Expr],
                  name: str, when: str) -> FunctionSpec:
    """``spec`` with its coordinates ``coords`` replaced by ``name``, M̂'s entries ``mass``
    (quantities of the spec's stage: M̂ at those coordinates) as an input: the same outputs,
    no M̂ evaluated. q must enter ``spec`` through M̂ only."""
    entries = tuple(sp.Symbol(f"{name}_{i}", real=True) for i in range(len(mass)))
    mapping: dict[sp.Basic, sp.Expr] = {}
    for m, x in zip(mass, entries, strict=True):
        if m.is_Symbol:
            mapping[m] = x
        elif (-m).is_Symbol:  # a stage names a negated quantity by its negation
            mapping[-m] = -x
    defs = {s: e.xreplace(mapping) for s, e in spec.definitions if s not in mapping}
    outputs = tuple(replace(o, exprs=tuple(sp.sympify(e).xreplace(mapping) for e in o.exprs))
                    for o in spec.outputs)
    definitions = definitions_read(defs, [e for o in outputs for e in o.exprs])
    read = {s for o in outputs for e in o.exprs for s in sp.sympify(e).free_symbols}
    read |= {s for _, e in definitions for s in e.free_symbols}
    if read & set(coords):
        raise ValueError(f"{spec.name}: q enters other than through Mhat")
    k = math.isqrt(len(mass))
    inputs = tuple(
        array(name, entries, f"Mhat({when}), {k}x{k} row-major (<f>_mhat)")
        if a.kind == "array" and a.symbols == tuple(coords) else a
        for a in spec.inputs
    )
    return replace(
        spec, name=f"{spec.name}_mhat", inputs=inputs, outputs=outputs,
        definitions=definitions,
        doc=spec.doc + f"\nThe same with {name} = Mhat({when}) in place of the coordinates:\n"
        "no Mhat evaluated (a step evaluates it once and keeps it for the next).",
    )


def minv_norm_needs_q(model: RobotModel) -> bool:
    """Whether the minimal formulation's ‖M̂⁻¹‖ depends on q (a robot with a trailer)."""
    return len(_minv_norm_spec(model, "minimal").inputs) > 1


@cache
def trig_angles(model: RobotModel, formulation: ctl.Formulation) -> tuple[int, ...]:
    """Coordinates whose sin and cos the ``_trig`` kernels take instead of q: those M̂ of
    ``formulation`` depends on (``ctl.mass_angles``). A controller step computes them once
    for the law at q and keeps them for (17) at q(t − h) in the next step. () when M̂ does
    not depend on q, or not through sin/cos of single coordinates only."""
    angles = ctl.mass_angles(formulation, model)
    if not angles:
        return ()
    mass = ctl.control_model(formulation, model).mass
    syms = tuple(model.q[i] for i in angles)
    if ctl.in_trig(mass, syms, ctl.trig_symbols("t", len(angles))) is None:
        return ()
    return angles


def _trig_variant(
    spec: FunctionSpec, coords: sp.Matrix, model: RobotModel, angles: tuple[int, ...],
    name: str, when: str,
) -> FunctionSpec:
    """``spec`` with its q argument ``coords`` replaced by ``name`` = (sin, cos) of the
    ``angles`` (the same outputs, no sin/cos evaluated)."""
    syms = tuple(coords[i] for i in angles)
    trig = ctl.trig_symbols(name, len(angles))
    outputs = []
    for o in spec.outputs:
        rewritten = ctl.in_trig(sp.Matrix(o.exprs), syms, trig)
        if rewritten is None:  # trig_angles checked M-hat, the only way q enters
            raise ValueError(f"{spec.name}: q enters other than through sin/cos of {syms}")
        outputs.append(replace(o, exprs=tuple(rewritten)))
    listed = ", ".join(f"sin, cos of {when}[{i}]" for i in angles)
    inputs = tuple(
        array(name, trig, listed) if a.kind == "array" and a.symbols == tuple(coords) else a
        for a in spec.inputs
    )
    return replace(
        spec, name=f"{spec.name}_trig", inputs=inputs, outputs=tuple(outputs),
        doc=spec.doc + f"\nThe same with {name} = ({listed}) in place of the coordinates:\n"
        "no sin/cos evaluated (a step computes them once and keeps them for the next).",
    )


# What a law kernel's common inputs are, for its header (an input may bring its own doc).
KERNEL_INPUT_DOCS = {
    "qdot": "measured qdot",
    "e": "q_des - q",
    "edot": "qdot_des - qdot",
    "qddot_des": "desired acceleration",
    "k1": "diagonal of K1",
    "k2": "diagonal of K2",
    "p12": "P entries per coordinate",
    "H1hat": "(17)",
}


def _kernel_input(arg: ctl.KernelArg, model: RobotModel) -> Argument:
    """A law kernel's input argument, documented (q: the measured coordinates)."""
    doc = arg.doc or (f"measured q ({words(model.nq)} coordinates)" if arg.name == "q"
                      else KERNEL_INPUT_DOCS.get(arg.name, ""))
    return array(arg.name, arg.values, doc)


@cache
def law_specs(model: RobotModel, controllers: tuple[ctl.ControllerSpec, ...] = ctl.REGISTRY
              ) -> tuple[FunctionSpec, ...]:
    """``<prefix>_laws``: the estimate's and the gains' pure kernels, and the law kernel of
    each of ``controllers`` (the registry's), each formulation."""
    specs: list[FunctionSpec] = []
    k1, k2, q1, q2 = sp.symbols("k1 k2 q1 q2", positive=True)
    p11, p12, p22 = ctl.lyapunov_p(k1, k2, q1, q2)
    specs.append(
        FunctionSpec(
            "lyapunov_p",
            "P = [[p11, p12], [p12, p22]] solving A^T P + P A = -diag(q1, q2) for one\n"
            "coordinate of (20), A = [[0, 1], [-k1, -k2]].",
            (array("gains", (k1, k2, q1, q2), "k1, k2, q1, q2"),),
            (out("P", [p11, p12, p22], "p11, p12, p22"),),
            ("(20)",),
        )
    )
    _, dnorms, dweights = ctl.tdroc_weighted_gain(MAX_WINDOW)
    # The newest norm apart from the kept ones, and its term added last: dn_1 is this
    # step's (from H1hat, through u(t-h): a chain through every step), the others are the
    # state's, read in place (the window after a push is the new norm, then the ring from
    # its new head's second entry); so one add, not the whole sum, waits for dn_1.
    older = sp.Symbol("dn_older_sum")
    older_sum = sum((dweights[i] * dnorms[i] for i in range(1, MAX_WINDOW)), sp.S.Zero)
    minv_norm = sp.Symbol("minv_norm", positive=True)
    specs.append(
        FunctionSpec(
            "tdroc_weighted_gain",
            "(25) from the window's difference norms dn_i = ||Omega(i) - Omega(i+1)||:\n"
            "khat = ||Mhat^-1||_F sum_i w_i dn_i (normalised weights, zero beyond the\n"
            "active window). Each dn_i is evaluated once, by <f>_omega_difference, when\n"
            "its newer Omega joins: dn_new is this step's, dn_kept the window's others.",
            (
                array("minv_norm", (minv_norm,), "from _minv_norm"),
                array("dn_new", (dnorms[0],), "dn_1, this step's"),
                array("dn_kept", tuple(dnorms[1:]), "dn_2 ..., newest first"),
                array("w", tuple(dweights), "weights"),
            ),
            (out("gain", [minv_norm * (older + dweights[0] * dnorms[0])]),),
            ("(25)",),
            definitions=((older, older_sum),),
        )
    )
    for f in model.formulations:
        tde, ts = ctl.tde_estimate(f, model)
        specs.append(
            FunctionSpec(
                f"{f}_tde",
                f"({f} formulation) (17): H1hat = u(t-h) - Mhat(q(t-h)) qddot(t-h), with\n"
                "qddot(t-h) = (qdot(t) - qdot(t-span)) / span (span = h backward, 2h central).",
                (
                    _nominal(model),
                    array("q_prev", ts.q_prev, "q(t-h)"),
                    array("u_prev", ts.u_prev, "u(t-h) applied"),
                    array("qdot_now", ts.qdot_now, "qdot(t)"),
                    array("qdot_then", ts.qdot_then, "qdot(t-span)"),
                    array("span", (ts.span,), "h or 2h"),
                ),
                (out("H1hat", tde),),
                ("(17)",),
                definitions=ctl.control_model(f, model).definitions(list(tde)),
            )
        )
        angles = trig_angles(model, f)
        if angles:
            specs.append(_trig_variant(specs[-1], ts.q_prev, model, angles, "trig_prev",
                                       "q(t-h)"))
        mhat = mhat_kernels(model, f)
        mass = list(ctl.control_model(f, model).mass)
        if mhat:  # (17) reading the M-hat the previous step kept
            stage = ctl.control_model(f, model).stage
            assert stage is not None
            prev = stage.substituted(mass, dict(zip(model.q, ts.q_prev, strict=True)))
            specs.append(_mhat_variant(specs[-1], tuple(ts.q_prev), prev, "mhat_prev",
                                       "q(t-h)"))
        specs.append(_minv_norm_spec(model, f))
        if mhat:
            specs.append(_mhat_variant(specs[-1], model.q, mass, "mhat", "q"))
            specs.append(_mhat_spec(model, f))
        gain, omega, w = ctl.tdroc_gain(f, MAX_WINDOW, model)
        specs.append(
            FunctionSpec(
                f"{f}_tdroc_gain",
                f"({f} formulation) (25):\n"
                "khat = ||Mhat^-1||_F sum_i w_i ||Omega(i) - Omega(i+1)||\n"
                "with normalised weights (zero beyond the active window).",
                (
                    array("minv_norm", (sp.Symbol("minv_norm", positive=True),),
                          "from _minv_norm"),
                    array("omega", tuple(omega), "row i is Omega(i+1)", shape=omega.shape),
                    array("w", tuple(w), "weights"),
                ),
                (out("gain", [gain]),),
                ("(25)",),
            )
        )
        dnorm, newer, older = ctl.omega_difference_norm(f, model)
        specs.append(
            FunctionSpec(
                f"{f}_omega_difference",
                f"({f} formulation) one term of (25): ||Omega(i) - Omega(i+1)|| of two\n"
                "consecutive rows of the window.",
                (
                    array("newer", tuple(newer), "Omega(i)"),
                    array("older", tuple(older), "Omega(i+1)"),
                ),
                (out("norm", [dnorm]),),
                ("(25)",),
            )
        )
        for c in controllers:
            if f not in c.formulations:
                continue
            kernel = ctl.kernel(c, f, model)
            specs.append(
                FunctionSpec(
                    f"{f}_{c.name}_law",
                    f"({f} formulation) {kernel.doc}",
                    (_nominal(model), *(_kernel_input(a, model) for a in kernel.inputs)),
                    tuple(out(a.name, list(a.values), a.doc) for a in kernel.outputs),
                    kernel.equations,
                    definitions=kernel.definitions,
                )
            )
            if c.trig and angles:
                specs.append(_trig_variant(specs[-1], model.q, model, angles, "trig", "q"))
            if c.trig and mhat:
                specs.append(_mhat_variant(specs[-1], model.q, mass, "mhat", "q"))
    return tuple(replace(s, bounded_trig=_trig_of_inputs_only(s)) for s in specs)


def _trig_of_inputs_only(spec: FunctionSpec) -> bool:
    """Whether every sin and cos of ``spec`` takes one input coordinate as it is, or the
    difference of two coordinates of one input array (a hitch angle θ_child − θ_root of
    the root-frame evaluation, ``ConstrainedSystem.root_frame_point``): then its argument is
    within twice the steps' input bound, which the bounded reduction covers
    (``FunctionSpec.bounded_trig``, ``TRIG_BOUND``). An angle formed from two arrays (the
    PI's heading error θ_des − θ, a reference against a measurement) keeps libm's, as
    before."""
    exprs = [e for a in spec.outputs for e in a.exprs] + [e for _, e in spec.definitions]
    inputs = set(spec.input_symbols())
    arrays = [set(a.all_symbols()) for a in spec.inputs if a.kind == "array"]

    def bounded(x: sp.Expr) -> bool:
        if x in inputs:
            return True
        terms = sp.Add.make_args(x)
        plus = [t for t in terms if t in inputs]
        minus = [-t for t in terms if t not in inputs and -t in inputs]
        return (len(terms) == 2 and len(plus) == len(minus) == 1
                and any({plus[0], minus[0]} <= s for s in arrays))

    trig = {f for e in exprs for f in sp.sympify(e).atoms(sp.sin, sp.cos)}
    return all(bounded(f.args[0]) for f in trig)


def plant_params_arg(model: RobotModel, name: str = "pp") -> Argument:
    return Argument(
        name,
        "params",
        ctype=f"{model.prefix}_plant_params_t",
        fields=_fields(model.plant_params),
        doc=model.docs.get("plant_params", "true parameters of the simulated robot"),
    )


@cache
def plant_specs(model: RobotModel) -> tuple[FunctionSpec, ...]:
    """``<prefix>_plant``: the simulated robot (issue 4) — the same machinery in the plant
    parameters (for the paper's robot, with the lateral first moment K_lat ≠ 0)."""
    s = model.plant_system
    n, m = model.nq, model.nu
    eta = tuple(model.qdot[i] for i in model.actuated)
    x = array("x", (*model.q, *eta), f"q ({n}), then the wheel rates ({m})")
    tau = array("tau", model.tau, "wheel torques after friction")
    staged = staged_forms(model, plant=True) if model.staged else None
    if staged is not None:
        xdot = staged.xdot
    else:
        eta_dot, _ = forward_dynamics_forms(model, s)
        xdot = sp.Matrix([*(s.null_space * sp.Matrix(eta)), *eta_dot])
    payload = array(
        "payload",
        model.payload,
        model.docs.get("payload", "payload mass, position ahead of and left of the root "
                       "body's frame origin"),
    )
    base = [model.payload_relations.get(p.symbol, p.symbol) for p in model.plant_params]
    keys = ", ".join(p.key for p in model.plant_params)
    return (
        FunctionSpec(
            "plant_state_derivative",
            model.docs.get("plant_state_derivative",
                           "x_dot = (S(q) eta, eta_dot) of the plant: the minimal form in the "
                           "plant\nparameters."),
            (plant_params_arg(model), x, tau),
            (out("xdot", xdot),),
            ("(9)", "(31)"),
            definitions=staged.stage.definitions_for(list(xdot)) if staged else (),
        ),
        FunctionSpec(
            "plant_params_with_payload",
            model.docs.get("plant_params_with_payload",
                           _wrap(f"Plant parameters ({keys}) of a robot carrying a point "
                                 "payload, from the kinetic energy of the loaded robot in "
                                 "the same base parameters (modeling.robot_model).")),
            (plant_params_arg(model, "base"), payload),
            (out("params", base),),
            (),
        ),
        *physical_specs(model),
    )


def physical_specs(model: RobotModel) -> tuple[FunctionSpec, ...]:
    """``plant_params_from_physical`` of a described robot (none for a lumped one): its
    base inertial parameters, payload included, from its physical quantities
    (``modeling.physical_map``; the wheel radii are not among them)."""
    pm = model.physical
    if pm is None:
        return ()
    keys = ", ".join(q.key for q in pm.inputs)
    return (
        FunctionSpec(
            "plant_params_from_physical",
            _wrap(f"Base inertial parameters ({', '.join(pm.outputs)}) of the robot whose "
                  "bodies, wheels and root payload have the given physical quantities "
                  "(modeling.physical_map: the same reduction as the model's)."),
            (array("phys", tuple(q.symbol for q in pm.inputs),
                   _wrap(f"{keys} (kg, kg m^2, m)")),),
            (out("base", list(pm.exprs)),),
            (),
        ),
    )
