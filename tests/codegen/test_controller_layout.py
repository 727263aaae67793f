"""The controller templates rendered for a layout other than Drishti's.

A made-up robot (prefix ``toy``, 8 coordinates, 2 inputs driving coordinates 4 and 5, no
paper formulation, ``||Mhat^-1||`` depending on q) exercises every generic path of the C
and Python controller templates. Its kernels do not exist, so the C is only inspected;
the Python module is compiled and run against stub kernels that check what they are
given. Drishti's byte-identical output is ``python -m codegen --check``.
"""

from __future__ import annotations

import dataclasses
import re
import sys
import types
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

from codegen import template_util
from codegen.backends.c.files import TEMPLATE_DIR as C_TEMPLATES
from codegen.backends.python.render import TEMPLATE_DIR as PY_TEMPLATES
from codegen.controller_api import (
    CONTROLLERS,
    MAX_ABS_INPUT,
    c_common_context,
    c_controller_context,
    defines,
    law_signature,
    python_context,
    status_codes,
)
from codegen.controller_layout import ControllerLayout, row_span, wrap_terms
from codegen.generate import layout_for
from codegen.robot_functions import MAX_WINDOW
from modeling.controllers import BASE_CHECKS
from modeling.robots.drishti.model import robot_model

TOY = ControllerLayout(
    prefix="toy",
    nq=8,
    nu=2,
    actuated=(4, 5),
    paper=False,
    minv_needs_q=True,
    coordinate_names=("x", "y", "theta", "phi", "theta_r", "theta_l", "psi", "chi"),
    input_names=("tau_r", "tau_l"),
)
# The same robot with its driven wheels first in q: the minimal formulation's slice (and
# the history it keeps) starts at row 0.
TOY_WHEELS_FIRST = dataclasses.replace(TOY, actuated=(0, 1))
TOY_PARAMS = ("J_theta", "J_phi", "K_x", "K_y", "radius_r", "radius_l")
TOY_CONDITION = ("p->J_theta * p->J_phi - p->K_x * p->K_x", "J_theta J_phi - K_x^2 > 0")
DRISHTI_LAYOUT = layout_for(robot_model())
PREAMBLE = ("Generated for tests/codegen/test_controller_layout.py",)
# The forward dynamics' guards as the C backend writes them (codegen.backends.c.backend
# .nominal_guards): a 2x2 S^T M S of the toy's parameters.
TOY_GUARDS = {
    "positive": [("p->radius_l", "radius_l > 0")],
    "temps": [("t0", "p->J_theta*p->radius_l")],
    "mbar": [("t0", ""), ("TOY_LIT(0.0)", ""), ("TOY_LIT(0.0)", ""), ("t0", "")],
    "minors": [("mbar[0]", "(S^T M S)[0][0] > 0"),
               ("mbar[0]*mbar[3] - mbar[1]*mbar[2]",
                "det(S^T M S) > 0: a positive-definite model")],
}


def _c_texts(layout: ControllerLayout) -> dict[str, str]:
    texts = {}
    for suffix in ("h", "c"):
        texts[f"controller.{suffix}"] = template_util.render(
            C_TEMPLATES,
            f"controller_common.{suffix}.jinja",
            preamble=PREAMBLE,
            layout=layout,
            param_fields=list(TOY_PARAMS),
            max_abs_input=MAX_ABS_INPUT,
            nominal_conditions=[TOY_CONDITION],
            nominal_guards=TOY_GUARDS,
            nominal_bounds=[(k, "-1000.0", "1000.0") for k in TOY_PARAMS],
            **c_common_context(),
        )
        for info in CONTROLLERS:
            texts[f"{info.name}.{suffix}"] = template_util.render(
                C_TEMPLATES,
                f"controller.{suffix}.jinja",
                preamble=PREAMBLE,
                layout=layout,
                c=info,
                max_abs_input=MAX_ABS_INPUT,
                # the step calls the laws module's kernels themselves (no private copies,
                # nothing kept: the backend adds those for a robot's real kernels)
                step_kernel_prefix=f"{layout.prefix}_", step_kernels="", kept_kernels=[],
                # the kernels' argument lists are the same for every robot: Drishti's
                **c_controller_context(info, list(TOY_PARAMS), layout, robot_model()),
            )
    texts["robot.h"] = template_util.render(
        C_TEMPLATES,
        "robot.h.jinja",
        preamble=PREAMBLE,
        layout=layout,
        robot_name="toy",
        robot_name_literal='"toy"',
        fields=[(k, "1.0") for k in TOY_PARAMS],
    )
    texts["example_main.c"] = template_util.render(
        C_TEMPLATES,
        "example_main.c.jinja",
        preamble=PREAMBLE,
        layout=layout,
        param_fields=list(TOY_PARAMS),
        heavier=["J_theta", "J_phi", "K_x", "K_y"],
    )
    return texts


def _python_text(layout: ControllerLayout) -> str:
    return template_util.render(
        PY_TEMPLATES,
        "controllers.py.jinja",
        preamble=PREAMBLE,
        layout=layout,
        status_codes=status_codes(layout),
        controllers=CONTROLLERS,
        law_signatures={c.name: law_signature(c, robot_model()) for c in CONTROLLERS},
        base_checks=BASE_CHECKS,
        formulation_paper=0,
        formulation_minimal=1,
        max_window=MAX_WINDOW,
        max_abs_input=MAX_ABS_INPUT,
        c_field_names={},
        param_keys=list(TOY_PARAMS),
        nominal_conditions=[('values["J_theta"] * values["J_phi"]', "'J_theta J_phi > 0'")],
        nominal_ranges={k: (-1000.0, 1000.0) for k in TOY_PARAMS},
        **python_context(),
    )


@pytest.fixture(scope="module")
def c_texts() -> dict[str, str]:
    return _c_texts(TOY)


def _function_body(text: str, name: str) -> str:
    """The body of C function ``name`` (from its definition to the closing brace)."""
    match = re.search(rf"^(?:static inline |\w+_STEP_INLINE )?\w+ {re.escape(name)}\("
                      r".*?^\{\n(.*?)^\}\n", text, re.S | re.M)
    assert match, f"no definition of {name}"
    return match.group(1)


def test_no_drishti_names_remain(c_texts: dict[str, str]) -> None:
    for name, text in {**c_texts, "controllers.py": _python_text(TOY)}.items():
        assert not re.search("wmr", text, re.I), f"{name} still names wmr"
        assert "toy" in text.lower(), name


def test_no_paper_kernels(c_texts: dict[str, str]) -> None:
    for name, text in c_texts.items():
        assert "_paper_" not in text, name
        assert "minv_paper" not in text, name
        assert not re.search(r"\bpaper\b ?\?", text), f"{name} branches on paper"
    py = _python_text(TOY)
    assert "laws.paper_" not in py
    assert "if paper" not in py


def test_sizes_come_from_the_layout(c_texts: dict[str, str]) -> None:
    for name in ("controller.h", "controller.c", "tdroc.h", "tdroc.c", "tdc.c", "asmc.c"):
        assert "[8]" in c_texts[name], name
        assert "[2]" in c_texts[name], name
        assert not re.search(r"_t \w+\[5\]", c_texts[name]), name  # no 5-wide array
    step = _function_body(c_texts["tdroc.c"], "toy_tdroc_step_of")
    assert "off = 4;" in step
    assert "out_tau[1] = u[1];" in step
    history = _function_body(c_texts["controller.h"], "toy_push_history")  # static inline
    # the history keeps the controlled rows 4, 5 only (u = tau there); q(t-h) all 8 (the
    # toy's (17) kernel reads q)
    assert "qdot_prev[i] = qdot[4 + i];" in history and "u_prev[i] = tau[i];" in history
    assert "for (i = 0; i < 2; ++i)" in history
    assert "for (i = 0; i < 8; ++i) {\n        q_prev[i] = q[i];" in history
    assert "toy_real_t qdot_prev[2];" in c_texts["tdroc.h"]
    assert (
        "toy_real_t k1[8];       /* diagonal of K1 (18), [GAIN_MIN, GAIN_MAX]; the minimal form "
        "uses k1[4], k1[5] */"
        in (c_texts["tdc.h"])
    )
    assert "writes tau[2] = (tau_r, tau_l)" in c_texts["roc.h"]


def test_formulation_paper_is_rejected(c_texts: dict[str, str]) -> None:
    base = _function_body(c_texts["controller.c"], "toy_check_base_config")
    assert "if (formulation != TOY_FORMULATION_MINIMAL)" in base
    assert "return toy_fail(detail, TOY_ERR_BAD_FORMULATION, TOY_FIELD_FORMULATION, -1);" in base
    assert "TOY_FORMULATION_MINIMAL" in c_texts["example_main.c"]


def test_minv_norm_is_evaluated_at_q_in_the_step(c_texts: dict[str, str]) -> None:
    tdroc = c_texts["tdroc.c"]
    step = _function_body(tdroc, "toy_tdroc_step_of")
    assert "toy_minimal_minv_norm(&cfg->nominal, q, &minv_norm);" in step
    assert "state->minv_norm = minv_norm;" in step  # committed with the rest
    assert "same_params" not in step
    init = _function_body(tdroc, "toy_tdroc_init")
    assert "minv_norm(" not in init
    assert "minv_for" not in c_texts["tdroc.h"]
    for name in ("tdc.c", "roc.c", "asmc.c"):
        assert "minv_norm" not in c_texts[name], name


def test_generic_nominal_check(c_texts: dict[str, str]) -> None:
    body = _function_body(c_texts["controller.c"], "toy_check_nominal")
    # The forward dynamics' guards written out (no call): S^T M S's minors over its entries.
    assert "toy_minimal_forward_dynamics" not in body
    assert "p->m" not in body
    assert "ok = ok && (mbar[0] > TOY_LIT(0.0));  /* (S^T M S)[0][0] > 0 */" in body
    assert "ok = ok && (mbar[0]*mbar[3] - mbar[1]*mbar[2] > TOY_LIT(0.0));" in body
    # Each parameter bounded, its index (struct order) in the error detail; no robot name in
    # the code: the values and their bounds in two arrays of struct order, one loop.
    values = body[body.index("const toy_real_t value["):body.index("};", body.index("value["))]
    assert [v.strip(" ,") for v in values.splitlines()[1:]].index("p->radius_l") == 5
    for table in ("lowest[", "highest["):
        bounds = body[body.index(table):body.index("};", body.index(table))].splitlines()[1:]
        assert "TOY_LIT(" in bounds[5] and bounds[5].endswith("/* radius_l */"), table
    assert (
        "if (!((value[i] >= lowest[i]) && (value[i] <= highest[i]))) {\n"
        "            return toy_fail(detail, TOY_ERR_BAD_NOMINAL, TOY_FIELD_NOMINAL, i);" in body
    )
    tdroc = c_texts["tdroc.c"]
    start = tdroc.index("static inline bool toy_tdroc_config_unchanged(")
    compared = tdroc[start:tdroc.index("\n}\n", start)]
    for value in ("q_vel", "held_gain"):
        assert (f"diff |= toy_real_bits(config->{value}) ^ toy_real_bits(kept->{value});"
                in compared), value
    # the nominal parameters through the one comparison in toy_controller.h
    assert "diff |= toy_nominal_diff(&config->nominal, &kept->nominal);" in compared
    header = c_texts["controller.h"]
    nominal = header[header.index("static inline toy_bits_t toy_nominal_diff("):]
    nominal = nominal[:nominal.index("\n}\n")]
    for field in ("J_theta", "radius_l"):
        assert f"diff |= toy_real_bits(a->{field}) ^ toy_real_bits(b->{field});" in nominal
    # every entry of an nq-vector: a loop of an even nq (vectorised), an odd one written out
    assert "for (i = 0; i < 8; ++i) {" in compared
    assert "diff |= toy_real_bits(config->k1[i]) ^ toy_real_bits(kept->k1[i]);" in compared
    # the ints as they are, their bits XOR-ed into the same word (one test for all)
    assert ("diff |= ((toy_bits_t)(unsigned int)config->formulation) ^ ((toy_bits_t)(unsigned "
            "int)kept->formulation);" in " ".join(compared.split()))
    # a float32 build (words of one size, no padding) compares the struct as one array
    assert "const uint64_t words = toy_words_diff(bytes, kept_bytes, 0, " in compared


def test_example_scatters_the_kinematics(c_texts: dict[str, str]) -> None:
    main = c_texts["example_main.c"]
    assert "toy_real_t pose_rates[6];" in main
    assert "toy_kinematics(&plant, q, &qdot[4], pose_rates);" in main
    assert "qdot[7] = pose_rates[5];" in main
    assert "qd_dot[4] = wheel_ref[0];" in main
    assert "plant.J_theta = nominal.J_theta * TOY_LIT(1.2);" in main
    assert "plant.radius_r" not in main


def test_api_tables_follow_the_layout() -> None:
    names = {s.name: s.value for s in status_codes(DRISHTI_LAYOUT)}
    assert names["WMR_OK"] == 0 and names["WMR_ERR_BAD_NOMINAL"] < 0
    names = [s.name for s in status_codes(TOY)]
    assert names[0] == "TOY_OK" and all(n.startswith("TOY_") for n in names)
    table = {name: value for name, value, _ in defines(TOY)}
    assert table["TOY_NQ"] == "8"
    assert table["TOY_STATE_MAGIC"] == "0x544f59"
    assert dict((n, v) for n, v, _ in defines(DRISHTI_LAYOUT))["WMR_STATE_MAGIC"] == "0x574d52"


def test_layout_helpers() -> None:
    assert DRISHTI_LAYOUT.PREFIX == "WMR"
    assert DRISHTI_LAYOUT.unactuated == (0, 1, 2)
    assert row_span(TOY.unactuated) == "1, 2, 3, 4, 7, 8"
    assert row_span(DRISHTI_LAYOUT.unactuated) == "1-3"
    assert TOY.scatter("tau", "0.0") == ["0.0"] * 4 + ["tau[0]", "tau[1]", "0.0", "0.0"]
    assert wrap_terms(["aa", "bb", "cc"], "x ", "  ", " + ", ";", width=9) == [
        "x aa + bb",
        "  + cc;",
    ]
    with pytest.raises(ValueError, match="consecutive"):
        ControllerLayout("toy", 8, 2, (4, 6), False, True, TOY.coordinate_names, ("a", "b"))
    with pytest.raises(ValueError, match="minimal formulation only"):
        ControllerLayout("toy", 8, 2, (4, 5), True, True, TOY.coordinate_names, ("a", "b"))


# ------------------------------------------------------------ the Python module, run


class _Stubs:
    """Kernels of the toy robot's ``toy_laws``/``toy_model`` that check their arguments."""

    def __init__(self) -> None:
        self.minv_q: list[np.ndarray] = []

    def laws(self) -> types.ModuleType:
        nq, nu = TOY.nq, TOY.nu
        mod = types.ModuleType("toy_laws")

        def sized(x: Any, n: int) -> np.ndarray:
            a = np.asarray(x, dtype=np.float64).reshape(-1)
            assert a.size == n, (a.size, n)
            return a

        def lyapunov_p(gains: Any) -> np.ndarray:
            sized(gains, 4)
            return np.array([1.0, 0.25, 0.5])

        def minimal_tde(q_prev: Any, up: Any, qdn: Any, qdthen: Any, span: Any, p: Any) -> Any:
            sized(q_prev, nq)
            for v in (up, qdn, qdthen):
                sized(v, nu)
            return np.full(nu, 0.1)

        def minimal_minv_norm(q: Any, p: Any) -> np.ndarray:
            self.minv_q.append(sized(q, nq).copy())
            return np.array([2.0])

        def minimal_tdroc_gain(minv: Any, om: Any, w: Any) -> np.ndarray:
            assert np.shape(om) == (MAX_WINDOW + 1, nu)
            sized(w, MAX_WINDOW)
            return np.array([float(minv[0])])

        def law(qv: Any, *args: Any) -> Any:
            sized(qv, nq)
            for v in args[:7]:
                sized(v, nu)
            return np.array([1.0, -1.0]), np.zeros(nu), np.array([0.5])

        def roc_law(qv: Any, qdv: Any, *args: Any) -> Any:
            sized(qdv, nq)
            u, s, sn = law(qv, *args)
            return u, s, sn, np.array([0.3])

        def tdc_law(qv: Any, *args: Any) -> Any:
            return law(qv, *args)[0]

        mod.__dict__.update(
            lyapunov_p=lyapunov_p,
            minimal_tde=minimal_tde,
            minimal_minv_norm=minimal_minv_norm,
            minimal_tdroc_gain=minimal_tdroc_gain,
            minimal_tdc_law=tdc_law,
            minimal_tdroc_law=law,
            minimal_roc_law=roc_law,
            minimal_asmc_law=roc_law,
        )
        return mod

    @staticmethod
    def model() -> types.ModuleType:
        mod = types.ModuleType("toy_model")

        def minimal_forward_dynamics(q: Any, rates: Any, tau: Any, p: Any) -> np.ndarray:
            assert np.size(q) == TOY.nq and np.size(rates) == TOY.nu == np.size(tau)
            if p["J_theta"] <= 0.0:
                raise ValueError("TOY_ERR_BAD_PARAMS: J_theta > 0")
            return np.zeros(TOY.nu)

        mod.minimal_forward_dynamics = minimal_forward_dynamics  # type: ignore[attr-defined]
        return mod


@pytest.fixture(params=[TOY, TOY_WHEELS_FIRST], ids=["wheels at 4", "wheels first"])
def toy_controllers(request: pytest.FixtureRequest) -> Iterator[tuple[Any, _Stubs]]:
    text = _python_text(request.param)
    code = compile(text, "toy_controllers.py", "exec")
    stubs = _Stubs()
    saved = {k: sys.modules.get(k) for k in ("toy_laws", "toy_model")}
    sys.modules["toy_laws"] = stubs.laws()
    sys.modules["toy_model"] = stubs.model()
    try:
        module = types.ModuleType("toy_controllers")
        module.__dict__["__name__"] = "toy_controllers"
        sys.modules["toy_controllers"] = module
        exec(code, module.__dict__)
        yield module, stubs
    finally:
        sys.modules.pop("toy_controllers", None)
        for k, v in saved.items():
            if v is None:
                sys.modules.pop(k, None)
            else:
                sys.modules[k] = v


def test_python_module_compiles() -> None:
    compile(_python_text(TOY), "toy_controllers.py", "exec")
    compile(_python_text(DRISHTI_LAYOUT), "controllers.py", "exec")


def test_python_controllers_run_on_the_layout(toy_controllers: tuple[Any, _Stubs]) -> None:
    mod, stubs = toy_controllers
    nominal = dict.fromkeys(TOY_PARAMS, 1.0)
    config = mod.Config(nominal=nominal, eps=0.5)
    assert config.formulation == mod.FORMULATION_MINIMAL
    with pytest.raises(mod.ControllerError) as err:
        mod.TDROC(mod.Config(nominal=nominal, formulation=mod.FORMULATION_PAPER))
    assert err.value.status == "TOY_ERR_BAD_FORMULATION"
    with pytest.raises(mod.ControllerError) as err:
        mod.TDC(mod.Config(nominal={**nominal, "J_theta": -1.0}))
    assert err.value.status == "TOY_ERR_BAD_NOMINAL"
    for cls in (mod.TDC, mod.TDROC, mod.ROC, mod.ASMC):
        ctrl = cls(config)
        zeros = np.zeros(TOY.nq)
        for k in range(5):
            q = np.full(TOY.nq, 0.01 * k)
            tau = ctrl.step(q, zeros, zeros, zeros, zeros)
            assert tau.shape == (TOY.nu,)
        assert ctrl.last_status == "TOY_OK"
        assert list(ctrl.u_prev) == [1.0, -1.0]  # the controlled rows only
        assert np.shape(ctrl.qdot_prev) == np.shape(ctrl.u_prev2) == (TOY.nu,)
        assert ctrl.u_discarded == 0.0
    # TDROC evaluated ||Mhat(q)^-1|| at q = 0 when its configuration was checked, then at the
    # measured q of each step once the gain was due.
    assert [float(q[0]) for q in stubs.minv_q] == pytest.approx([0.0, 0.03, 0.04])


def test_any_robot_name_gives_a_valid_c_string(tmp_path: Any) -> None:
    """Quotes, backslashes, control characters, '?' (trigraphs) and UTF-8 in a robot's name
    come out of the C string literal byte for byte."""
    import subprocess

    from codegen.backends.c.backend import c_string

    name = 'my "robot" \\ v2?? \t*/ é'
    src = tmp_path / "name.c"
    src.write_text("#include <stdio.h>\nint main(void) { fputs(" + c_string(name)
                   + ", stdout); return 0; }\n")
    exe = tmp_path / "name"
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Werror", "-o", str(exe), str(src)], check=True)
    assert subprocess.run([str(exe)], capture_output=True, check=True).stdout == name.encode()
