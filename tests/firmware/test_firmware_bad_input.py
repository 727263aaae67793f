"""Bad input to the generated C controllers (cffi, double build): every case of
``runtime.tooling.bad_input`` returns its own documented status code, leaves the state's
bytes and tau unchanged, and the next valid step equals that of a twin that never saw
the bad input; saturation is clipped and reported. ``docs/BAD_INPUT.md`` is the table
the same code produces. Also the TDE condition ‖M⁻¹M̂ − I‖ < 1 over a parameter box
(``runtime.bindings.uncertainty``) and the checks a configuration passes before it is run
(``runtime.stability.checks``)."""

from __future__ import annotations

import math

import pytest

from codegen.controller_api import status_codes
from codegen.generate import layout_for
from modeling.robots.drishti.model import robot_model
from runtime.bindings import cbuild
from runtime.bindings.config import controller_config
from runtime.bindings.generated import load_robot_code
from runtime.bindings.uncertainty import check_tde, tde_alpha
from runtime.experiment.settings import Experiment
from runtime.stability.checks import check_configuration
from runtime.tooling.bad_input import cases as bad_cases
from runtime.tooling.bad_input import runner, table

STATUS_CODES = status_codes(layout_for(robot_model()))
CODE = load_robot_code("")  # Drishti's generated code
DRISHTI = bad_cases.DRISHTI
CASES = bad_cases.cases(8)


@pytest.fixture(scope="module")
def lib() -> cbuild.CLibrary:
    return cbuild.build(False)


@pytest.fixture(scope="module")
def outcomes(lib: cbuild.CLibrary) -> list[runner.Outcome]:
    return runner.run_all(lib)


def test_c_status_enum_is_the_documented_one(lib: cbuild.CLibrary) -> None:
    assert runner.status_names(lib) == {s.value: s.name for s in STATUS_CODES}
    assert bad_cases.max_window(lib) == 8
    assert [c.id for c in bad_cases.cases(bad_cases.max_window(lib))] == [c.id for c in CASES]


def test_case_ids_are_unique() -> None:
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids))


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input_case(lib: cbuild.CLibrary, case: bad_cases.Case) -> None:
    values = runner.status_values(lib)
    runs = [
        runner.run_case(lib, name, form, case)
        for name in bad_cases.CONTROLLERS
        if name in case.applies
        for form in bad_cases.CONTROLLER_FORMULATIONS[name]
    ]
    assert runs
    for o in runs:
        assert o.status == values[case.expected], (o.controller, o.formulation, o.status)
    assert runner.failures(runs, lib) == []
    if case.kind in ("input", "config", "null"):
        assert all(o.twin_equal for o in runs)
    if case.kind == "config":
        assert all(o.init_status == o.check_status == o.status for o in runs)


def test_every_documented_status_is_exercised(outcomes: list[runner.Outcome]) -> None:
    seen = {o.case.expected for o in outcomes}
    unreachable_by_step = {
        "WMR_OK",  # success
        "WMR_ERR_NONFINITE_INPUT",  # model functions only (see test_firmware_fuzz)
        "WMR_ERR_BAD_PARAMS",  # model functions only
        "WMR_ERR_NONFINITE_OUTPUT",  # needs finite, bounded inputs giving inf: fuzzed
        "WMR_WARN_TRACTION",  # wmr_traction_check only (tests/generated/test_contact_forces.py)
        "WMR_ERR_BAD_TRACTION",  # the traction functions only (the same tests)
        "WMR_WARN_UNCERTIFIED",  # the within_certificate checks only (test_within_certificate)
    }
    assert seen | unreachable_by_step == {s.name for s in STATUS_CODES}


def test_doc_equals_the_scripts_output(
    lib: cbuild.CLibrary, outcomes: list[runner.Outcome]
) -> None:
    assert runner.failures(outcomes, lib) == []
    text = table.render(outcomes, runner.status_names(lib), table.alpha_rows())
    assert table.DOC.exists(), "run `python -m runtime.tooling.bad_input.table`"
    assert table.DOC.read_text() == text, (
        "docs/BAD_INPUT.md is stale: run `python -m runtime.tooling.bad_input.table`"
    )


# ------------------------------------------------------------------ the TDE condition
def test_check_nominal_accepts_the_robot() -> None:
    for form in ("paper", "minimal"):
        alpha = check_tde(CODE, DRISHTI, 0.3, formulation=form)
        assert 0.3 < alpha < 0.6, alpha  # ±30 % around an exact model
        assert check_tde(CODE, DRISHTI, 0.0, formulation=form) == pytest.approx(0.0, abs=1e-12)


def test_check_nominal_rejects_a_nominal_three_times_too_heavy() -> None:
    heavy = {**DRISHTI, "m": 3 * DRISHTI["m"], "I": 3 * DRISHTI["I"], "K": 3 * DRISHTI["K"]}
    for form in ("paper", "minimal"):
        with pytest.raises(ValueError, match=r"TDE condition \|\|M\^-1 Mhat - I\|\| < 1"):
            check_tde(CODE, heavy, 0.3, true_params=DRISHTI, formulation=form)
        assert tde_alpha(CODE, heavy, 0.3, true_params=DRISHTI, formulation=form)[0] > 2.0


def test_check_nominal_alpha_grows_with_the_box() -> None:
    alphas = [check_tde(CODE, DRISHTI, box, formulation="paper")
              for box in (0.05, 0.1, 0.2, 0.3)]
    assert alphas == sorted(alphas)
    with pytest.raises(ValueError, match="TDE condition"):
        check_tde(CODE, DRISHTI, 0.6, formulation="paper")  # true robots down to 40 %


@pytest.mark.parametrize(
    ("nominal", "box", "match"),
    [
        ({**DRISHTI, "m": 0.0}, 0.3, "violate m > 0"),
        ({**DRISHTI, "K": math.nan}, 0.3, "'K' must be finite"),
        ({**DRISHTI, "I": 0.001}, 0.3, "m I - K\\^2"),
        ({k: v for k, v in DRISHTI.items() if k != "d"}, 0.3, "missing parameter"),
        (DRISHTI, 1.0, "box must be in"),
        (DRISHTI, -0.1, "box must be in"),
    ],
)
def test_check_nominal_rejects_invalid_arguments(
    nominal: dict[str, float], box: float, match: str
) -> None:
    with pytest.raises(ValueError, match=match):
        check_tde(CODE, nominal, box, formulation="paper")


def test_checked_controller_config(lib: cbuild.CLibrary) -> None:
    exp = Experiment()
    check_configuration(CODE, "tdroc", "paper", dict(DRISHTI), exp, DRISHTI)
    cfg = controller_config(lib, CODE, "tdroc", "paper", dict(DRISHTI), exp)
    state = lib.ffi.new("wmr_tdroc_state_t *")
    assert lib.lib.wmr_tdroc_init(state, cfg) == 0
    heavy = {**DRISHTI, "m": 108.0, "I": 17.16, "K": 1.02}
    with pytest.raises(ValueError, match="TDE condition"):
        check_configuration(CODE, "tdc", "minimal", heavy, exp, DRISHTI)
    # ROC/ASMC do not use the time-delay estimate: no check.
    check_configuration(CODE, "asmc", "paper", heavy, exp, DRISHTI)
