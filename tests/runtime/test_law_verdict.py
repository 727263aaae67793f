"""A controller added to the registry gets its own sampled-data verdict, from its generated
law (issue 46), or a sentence saying why not.

Two toys are declared here with ``modeling.controllers``' declaration API, appended to a
copy of the registry and generated for Drishti into a temporary folder (as
tests/codegen/test_controller_declaration.py does): ``pd``, a plain PD on the wheel
angles, τ = K1 e + K2 ė (no model, no estimate; the K1, K2 fields the old analysis
recognised as the computed-torque law of (18) and gave that law's verdict, spectral radius
0.85349), and ``pdabs``, the same with a term K2 |ė| that has a kink where the loop runs
(ė = 0 on the steady circle): the analysis must refuse it, naming it.

The PD's verdict is checked against the closed loop simulated by the runtime (the generated
C, compiled, on the generated plant): the largest stable rate gain K2 predicted from the
linearised law and the one found by bisecting simulated runs agree within 15 %.
About 40 s on one core (the derivation, gcc, a dozen linearisations and runs).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterator
from dataclasses import replace

import numpy as np
import pytest
import sympy as sp

from codegen.generate import generate_files
from modeling import controllers as ctl
from modeling.controllers import REGISTRY, ControllerSpec, Estimate, Kernel, KernelArg
from modeling.controllers.declaration import law_args
from modeling.controllers.model import Formulation
from modeling.robot_file import load_robot_model
from modeling.robot_model import RobotModel
from runtime.bindings.generated import RobotCode, load_robot_code
from runtime.experiment.settings import Experiment
from runtime.plants import plant_for
from runtime.sim import loop, paths
from runtime.stability import analysis
from runtime.stability.sampled_loop import NotLinearisable, pencil, setting
from runtime.stability.verification import linear_experiment

TDC_RADIUS = 0.85349  # the computed-torque verdict the old analysis gave any K1, K2 law


def _pd_kernel(formulation: Formulation, model: RobotModel, kink: bool = False) -> Kernel:
    """τ = K1 e + K2 ė (+ K2 |ė| with ``kink``) on the controlled coordinates."""
    cm = ctl.control_model(formulation, model)
    ls = ctl.law_symbols(cm.size)
    u = [ls.k1[i] * ls.e[i] + ls.k2[i] * ls.edot[i]
         + (ls.k2[i] * sp.Abs(ls.edot[i]) if kink else 0) for i in range(cm.size)]
    return Kernel(
        "toy plain PD: u = K1 e + K2 edot" + (" + K2 |edot|." if kink else "."), (),
        law_args(ls, "e", "edot", "k1", "k2"),
        (KernelArg("u", "u", tuple(u)),),
    )


def _pdabs_kernel(formulation: Formulation, model: RobotModel) -> Kernel:
    return _pd_kernel(formulation, model, kink=True)


PD = ControllerSpec("pd", "PD", "toy plain PD", "none", _pd_kernel, Estimate.NONE,
                    formulations=("minimal",))
PDABS = ControllerSpec("pdabs", "PDABS", "toy PD with a kink", "none", _pdabs_kernel,
                       Estimate.NONE, formulations=("minimal",))
PACKAGE = "toy_law_verdict"


@pytest.fixture(scope="module")
def code(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RobotCode]:
    """Drishti's code with the toys registered, in a folder of its own."""
    model, robot = load_robot_model(None)
    root = tmp_path_factory.mktemp("toy") / PACKAGE
    for name, data in generate_files(robot, model, report=False,
                                     controllers=(*REGISTRY, PD, PDABS)).items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    yield load_robot_code(root)
    for name in [m for m in sys.modules if m.startswith("_generated_")]:
        if getattr(sys.modules[name], "__file__", "") and str(root) in str(
                sys.modules[name].__file__):
            del sys.modules[name]


def with_k2(exp: Experiment, k2: float) -> Experiment:
    return replace(exp, controller=replace(exp.controller, k2=k2))


def predicted_stable(code: RobotCode, exp: Experiment, k2: float) -> bool:
    s = setting(code, "pd", "minimal", dict(code.params), with_k2(exp, k2))
    return pencil(s).radius(0.0) < 1.0


def simulated_stable(code: RobotCode, exp: Experiment, k2: float) -> bool:
    """The runtime's closed loop (generated C and plant) on the analysed circle: stable
    when it runs to the end with its error not growing (as
    :func:`runtime.stability.verification.simulated_unstable` judges)."""
    lin = linear_experiment(with_k2(exp, k2))
    robot = dict(code.params)
    r = loop.run(code, "pd", "minimal", paths.circle(code, robot, lin), robot, lin,
                 plant=plant_for(code, lin, robot))
    if r.failed_at is not None or not np.all(np.isfinite(r.error_norm)):
        return False
    n = len(r.error_norm)
    middle = float(np.max(r.error_norm[n // 3 : 2 * n // 3]))
    last = float(np.max(r.error_norm[2 * n // 3 :]))
    return last <= 3.0 * max(middle, 1e-12) and float(r.error_norm.max()) < 10.0


def boundary(stable: object, lo: float, hi: float, rel_tol: float = 0.02) -> float:
    """The largest K2 in [lo, hi] judged stable, by bisection (lo stable, hi not)."""
    assert callable(stable)
    assert stable(lo) and not stable(hi), (lo, hi)
    while hi - lo > rel_tol * hi:
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return 0.5 * (lo + hi)


def test_toy_pd_gets_its_own_verdict(code: RobotCode) -> None:
    """Not the computed-torque verdict: the PD's own law, and no switching gain."""
    a = analysis.analyse(code, "pd", "minimal", dict(code.params), Experiment(), measure=False)
    assert abs(a.radius_without_switching - TDC_RADIUS) > 1e-3
    assert math.isinf(a.max_stable_gain) and a.gain_at_setting == 0.0
    pen = pencil(setting(code, "pd", "minimal", dict(code.params), Experiment()))
    assert pen.about == "the closed loop's steady motion"
    assert not any(n.startswith("law.H1hat") for n in pen.names)  # no estimate in its loop


def test_toy_pd_boundary_agrees_with_simulation(code: RobotCode) -> None:
    """The largest stable K2: predicted from the linearised generated law, and found in the
    simulated closed loop; within 15 %."""
    exp = Experiment()
    predicted = boundary(lambda k2: predicted_stable(code, exp, k2), 0.5, 64.0)
    simulated = boundary(lambda k2: simulated_stable(code, exp, k2), 0.5, 64.0)
    assert abs(predicted - simulated) <= 0.15 * simulated, (predicted, simulated)


def test_toy_with_a_kink_is_refused_naming_it(code: RobotCode) -> None:
    with pytest.raises(NotLinearisable, match=r"PDABS \(pdabs/minimal\): not differentiable"):
        pencil(setting(code, "pdabs", "minimal", dict(code.params), Experiment()))
    refused: list[str] = []
    rows = analysis.analyse_all(code, dict(code.params), Experiment(), measure=False,
                                refused=refused)
    assert "pdabs" not in {r.controller for r in rows} and "pd" in {r.controller for r in rows}
    assert any(line.startswith("* PDABS minimal: no sampled-data verdict") for line in refused)
