"""The WMR's generated functions: the symbolic model and control laws of ``modeling``
wrapped as FunctionSpecs with named, documented inputs and outputs.

Modules (one C ``.h``/``.c`` pair, one Python module, one set of CasADi functions each):

* ``wmr_model``: M and H of (14), forward dynamics, kinematics (31), the minimal form and
  the linearisation of the state equation x = (q, θ̇_r, θ̇_l).
* ``wmr_laws``: the controllers' pure kernels — the time-delay estimate (17), the
  TDROC gain (25), the four laws, P of the Lyapunov equation — for both formulations.
  The controller step functions (``wmr_tdroc_step`` …) are templates around these that
  own validation, history and status; they do no arithmetic of their own beyond copying.
"""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import sympy as sp

from codegen.spec import Argument, Field, FunctionSpec, Guard
from modeling import controllers as ctl
from modeling import wmr

PARAM_FIELDS: tuple[tuple[str, sp.Symbol, str], ...] = (
    ("m", wmr.m, "total mass [kg]"),
    ("I", wmr.I_z, "yaw inertia about C [kg m^2] (C field Iz)"),
    ("K", wmr.K, "first moment of mass behind C [kg m]"),
    ("Iw", wmr.I_w, "wheel spin inertia [kg m^2]"),
    ("r", wmr.r, "wheel radius [m]"),
    ("b", wmr.b, "track width [m]"),
    ("d", wmr.d, "C ahead of the axle midpoint [m]"),
)
PARAM_KEYS = tuple(name for name, _, _ in PARAM_FIELDS)
MAX_WINDOW = 8  # TDROC's largest n (compile-time history size)

STATUS_NONFINITE_INPUT = "WMR_ERR_NONFINITE_INPUT"
STATUS_BAD_PARAMS = "WMR_ERR_BAD_PARAMS"
STATUS_NONFINITE_OUTPUT = "WMR_ERR_NONFINITE_OUTPUT"


def params_arg(name: str = "p", doc: str = "lumped robot parameters") -> Argument:
    return Argument(
        name,
        "params",
        fields=tuple(Field(n, (s,), doc=d) for n, s, d in PARAM_FIELDS),
        doc=doc,
    )


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


def _param_guards() -> tuple[Guard, ...]:
    s = wmr.wmr_system()
    # The same grouped entries as compact_forward_dynamics, so CSE shares them.
    mbar = s.minimal_mass_matrix.applyfunc(wmr.compact_form)
    det = mbar[0, 0] * mbar[1, 1] - mbar[0, 1] * mbar[1, 0]
    return (
        Guard(STATUS_BAD_PARAMS, wmr.r, "r > 0"),
        Guard(STATUS_BAD_PARAMS, wmr.b, "b > 0"),
        # Sylvester: both leading minors of S^T M S positive <=> positive definite.
        Guard(STATUS_BAD_PARAMS, mbar[0, 0], "(S^T M S)[0][0] > 0"),
        Guard(STATUS_BAD_PARAMS, det, "det(S^T M S) > 0: a positive-definite model"),
    )


@cache
def model_specs() -> tuple[FunctionSpec, ...]:
    """``wmr_model``: the functions the C API of issue 3 names."""
    s = wmr.wmr_system()
    q = array("q", wmr.q, "x_c, y_c, theta, theta_r, theta_l")
    qdot = array("qdot", wmr.qdot, "generalised velocities")
    eta = tuple(wmr.qdot[3:])
    wheel_rates = array("wheel_rates", eta, "theta_r rate, theta_l rate")
    tau = array("tau", wmr.tau, "wheel torques tau_r, tau_l")
    p = params_arg()
    # Evaluation forms (equal to reduced_/minimal_forward_dynamics; tests check it).
    eta_dot, qdd = s.compact_forward_dynamics(wmr.tau, wmr.compact_form)
    # State x = (q, η): ẋ = (S(q) η, η̇(q, η, τ)); its Jacobians linearise the robot.
    x = sp.Matrix([*wmr.q, *eta])
    xdot = sp.Matrix([*(s.null_space * sp.Matrix(eta)), *eta_dot])
    jac_x = xdot.jacobian(x)
    jac_u = xdot.jacobian(wmr.tau)
    guards = _param_guards()

    def checked(spec: FunctionSpec) -> FunctionSpec:
        return replace(
            spec,
            returns_status=True,
            guards=guards,
            nonfinite_input=STATUS_NONFINITE_INPUT,
            nonfinite_output=STATUS_NONFINITE_OUTPUT,
        )

    return (
        FunctionSpec(
            "mass_matrix",
            "M(q) of (14), the reduced (multiplier-free) mass matrix; not symmetric.",
            (p, q),
            (out("M", s.reduced_mass_matrix, "5x5 row-major"),),
            ("(14)",),
        ),
        FunctionSpec(
            "bias_forces",
            "H(q, qdot) of (14). Rows 1-3 hold the velocity-product terms of the twice\n"
            "differentiated constraints; valid for qdot on the constraint manifold.",
            (p, q, qdot),
            (out("H", s.reduced_bias),),
            ("(14)",),
        ),
        checked(
            FunctionSpec(
                "forward_dynamics",
                "qddot solving (14) with u = B tau, by structured elimination:\n"
                "eta_dot = (S^T M S)^-1 (tau - S^T(M Sdot eta + H)),\n"
                "qddot = S eta_dot + Sdot eta.\n"
                "Only the wheel rates qdot[3], qdot[4] are read: the other velocities follow\n"
                "from the constraints (6)-(8).",
                (p, q, qdot, tau),
                (out("qddot", qdd),),
                ("(9)", "(14)", "(31)"),
            )
        ),
        FunctionSpec(
            "kinematics",
            "(31): pose rates (x_c, y_c, theta) from the wheel rates, xi_dot = S_d(q) eta.",
            (p, q, wheel_rates),
            (out("pose_rates", s.null_space[:3, :] * sp.Matrix(eta)),),
            ("(31)", "(13)"),
        ),
        FunctionSpec(
            "minimal_mass_matrix",
            "Mbar = S^T M S of the minimal two-coordinate model (constant for K_lat = 0).",
            (p, q),
            (out("M", s.minimal_mass_matrix, "2x2 row-major"),),
            ("(9)",),
        ),
        FunctionSpec(
            "minimal_bias_forces",
            "Hbar = S^T (M Sdot eta + H) of the minimal model.",
            (p, q, wheel_rates),
            (out("H", s.minimal_bias),),
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
            "Jacobians of the state equation x_dot = f(x, tau), x = (q, theta_r rate,\n"
            "theta_l rate), f = (S(q) eta, eta_dot): A = df/dx (7x7), B = df/dtau (7x2).",
            (p, q, wheel_rates, tau),
            (out("A", jac_x, "7x7 row-major"), out("B", jac_u, "7x2 row-major")),
            ("(9)", "(31)"),
        ),
    )


def _nominal(doc: str = "nominal parameters of M-hat") -> Argument:
    return params_arg("p", doc)


@cache
def law_specs() -> tuple[FunctionSpec, ...]:
    """``wmr_laws``: pure kernels of the four controllers, both formulations."""
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
    theta_q = array("q", wmr.q, "measured q (five coordinates)")
    for f in ctl.FORMULATIONS:
        cm = ctl.control_model(f)
        n = cm.size
        tde, ts = ctl.tde_estimate(f)
        specs.append(
            FunctionSpec(
                f"{f}_tde",
                f"({f} formulation) (17): H1hat = u(t-h) - Mhat(q(t-h)) qddot(t-h), with\n"
                "qddot(t-h) = (qdot(t) - qdot(t-span)) / span (span = h backward, 2h central).",
                (
                    _nominal(),
                    array("q_prev", ts.q_prev, "q(t-h)"),
                    array("u_prev", ts.u_prev, "u(t-h) applied"),
                    array("qdot_now", ts.qdot_now, "qdot(t)"),
                    array("qdot_then", ts.qdot_then, "qdot(t-span)"),
                    array("span", (ts.span,), "h or 2h"),
                ),
                (out("H1hat", tde),),
                ("(17)",),
            )
        )
        specs.append(
            FunctionSpec(
                f"{f}_minv_norm",
                f"({f} formulation) ||Mhat^-1||_F of (25). Mhat(theta) = T Mhat(0) T^T with T\n"
                "an orthogonal heading rotation, so the norm depends on the parameters only.",
                (_nominal(),),
                (out("norm", [ctl.mass_inverse_norm(f)]),),
                ("(25)",),
            )
        )
        gain, omega, w = ctl.tdroc_gain(f, MAX_WINDOW)
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
        common = lambda ls: (  # noqa: E731 - the argument list every law shares
            array("e", ls.e, "q_des - q"),
            array("edot", ls.edot, "qdot_des - qdot"),
            array("qddot_des", ls.qddot_des, "desired acceleration"),
            array("k1", ls.k1, "diagonal of K1"),
            array("k2", ls.k2, "diagonal of K2"),
            array("p12", ls.p12, "P entries per coordinate"),
            array("p22", ls.p22, ""),
        )
        law, ls = ctl.tde_law(f, switching=False)
        specs.append(
            FunctionSpec(
                f"{f}_tdc_law",
                f"({f} formulation) TDC (16), (18): u = Mhat(q) ua_hat + H1hat.",
                (_nominal(), theta_q, *common(ls), array("H1hat", ls.h1, "(17)")),
                (out("u", law.u),),
                ("(16)", "(18)"),
            )
        )
        law, ls = ctl.tde_law(f, switching=True)
        specs.append(
            FunctionSpec(
                f"{f}_tdroc_law",
                f"({f} formulation) TDROC (16), (22), (25):\n"
                "u = Mhat(q)(ua_hat + gain s/max(|s|, eps))\n"
                "+ H1hat, s = B^T P e.",
                (
                    _nominal(),
                    theta_q,
                    *common(ls),
                    array("H1hat", ls.h1, "(17)"),
                    array("gain", (ls.gain,), "khat of (25)"),
                    array("eps", (ls.eps,), "boundary layer"),
                ),
                (out("u", law.u), out("s", law.s), out("s_norm", [law.s_norm])),
                ("(16)", "(22)", "(24)", "(25)"),
            )
        )
        qdot_c = array("qdot", wmr.qdot, "measured qdot")
        law, ls = ctl.model_law(f, "roc")
        specs.append(
            FunctionSpec(
                f"{f}_roc_law",
                f"({f} formulation) ROC:\n"
                "u = Mhat(q)(ua_hat + rho s/max(|s|, eps)) + Hhat(q, qdot),\n"
                "rho = (alpha(|qddot_des| + |K1 e + K2 edot|) + phi)/(1 - alpha).",
                (
                    _nominal(),
                    theta_q,
                    qdot_c,
                    *common(ls),
                    array("bounds", (ls.alpha, ls.phi), "alpha, phi"),
                    array("eps", (ls.eps,), ""),
                ),
                (
                    out("u", law.u),
                    out("s", law.s),
                    out("s_norm", [law.s_norm]),
                    out("gain", [law.gain]),
                ),
                ("(22)", "(24)"),
            )
        )
        law, ls = ctl.model_law(f, "asmc")
        gamma, h = sp.symbols("gamma h", positive=True)
        specs.append(
            FunctionSpec(
                f"{f}_asmc_law",
                f"({f} formulation) ASMC:\n"
                "u = Mhat(q)(ua_hat + khat s/max(|s|, eps)) + Hhat(q, qdot);\n"
                "gain_next = khat + h gamma |s|.",
                (
                    _nominal(),
                    theta_q,
                    qdot_c,
                    *common(ls),
                    array("gain", (ls.gain,), "khat"),
                    array("eps", (ls.eps,), ""),
                    array("adapt", (gamma, h), "gamma, h"),
                ),
                (
                    out("u", law.u),
                    out("s", law.s),
                    out("s_norm", [law.s_norm]),
                    out("gain_next", [ctl.asmc_adaptation(ls.gain, gamma, law.s_norm, h)]),
                ),
                ("(22)", "(24)"),
            )
        )
        del n
    return tuple(specs)


PLANT_FIELDS: tuple[tuple[str, sp.Symbol, str], ...] = (
    *PARAM_FIELDS[:3],
    ("K_lat", wmr.K_lat, "first moment of mass left of C [kg m] (off-axis payload)"),
    *PARAM_FIELDS[3:],
)


def plant_params_arg(name: str = "pp") -> Argument:
    return Argument(
        name,
        "params",
        ctype="wmr_plant_params_t",
        fields=tuple(Field(n, (s,), doc=d) for n, s, d in PLANT_FIELDS),
        doc="true parameters of the simulated robot, including K_lat",
    )


@cache
def plant_specs() -> tuple[FunctionSpec, ...]:
    """``wmr_plant``: the simulated robot (issue 4) — the same machinery with K_lat ≠ 0."""
    s = wmr.wmr_system(lateral_moment=True)
    eta = tuple(wmr.qdot[3:])
    x = array("x", (*wmr.q, *eta), "q (5), then the wheel rates (2)")
    tau = array("tau", wmr.tau, "wheel torques after friction")
    eta_dot, _ = s.compact_forward_dynamics(wmr.tau, wmr.compact_form)
    xdot = sp.Matrix([*(s.null_space * sp.Matrix(eta)), *eta_dot])
    rel = wmr.payload_relations()
    payload = array(
        "payload",
        (wmr.m_L, wmr.x_L, wmr.y_L),
        "payload mass, position ahead of C, position left of C",
    )
    base = [rel.get(sym, sym) for _, sym, _ in PLANT_FIELDS]
    return (
        FunctionSpec(
            "plant_state_derivative",
            "x_dot = (S(q) eta, eta_dot) of the plant: the minimal form derived with the\n"
            "lateral first moment K_lat (an off-axis payload).",
            (plant_params_arg(), x, tau),
            (out("xdot", xdot),),
            ("(9)", "(31)"),
        ),
        FunctionSpec(
            "plant_params_with_payload",
            "Plant parameters (m, I, K, K_lat, Iw, r, b, d) of a robot carrying a point payload,\n"
            "from the Hessian of the combined kinetic energy (modeling.wmr.payload_relations).",
            (plant_params_arg("base"), payload),
            (out("params", base),),
            (),
        ),
    )
