"""What a controller configuration must pass before it is run: the toolchain refuses to
run one it predicts will fail (every reproduction run,
:func:`runtime.reproduction.runs.checked_run`, on every robot).

* The TDE condition ‖M⁻¹ M̂ − I‖ < 1 of (17) over the experiment's uncertainty box
  (``controller.uncertainty``), for the controllers with the time-delay estimate
  (:func:`runtime.bindings.uncertainty.check_tde`).
* The sampled closed loop's predicted stability without switching gain, where the analysis
  covers the robot and the law (:func:`runtime.stability.sampled_loop.check_sampled_loop`).

Both raise ``ValueError`` naming the reason.
"""

from __future__ import annotations

from collections.abc import Mapping

from runtime.bindings.generated import RobotCode
from runtime.bindings.uncertainty import check_tde
from runtime.experiment.settings import Experiment
from runtime.stability.sampled_loop import check_sampled_loop, covers, refusal


def check_configuration(code: RobotCode, name: str, formulation: str,
                        nominal: Mapping[str, float], exp: Experiment,
                        true_params: Mapping[str, float] | None = None) -> None:
    """Raise ``ValueError`` if ``name`` in ``formulation`` fails a check (see the module
    docstring); ``true_params``: the centre of the box of true robots (default: nominal)."""
    info = code.controller(name)
    if info.tde:
        check_tde(code, nominal, exp.controller.uncertainty, true_params=true_params,
                  formulation=formulation)
    if covers(code) and not refusal(info):
        check_sampled_loop(code, name, formulation, dict(nominal), exp)
