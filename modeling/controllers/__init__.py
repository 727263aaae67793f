"""The controllers of Roy et al. (2017) as symbolic laws (TDC, TDROC, ROC, ASMC) and the
wheel-velocity PI baseline, one file each, declared (``declaration``) and registered
(``registry``).

Every law acts on a model  M(q) q̈ + H(q, q̇) = u  in one of two formulations (``model``):

* ``paper``: the five coordinates of (14), M = M̃(q) (not symmetric), u = B τ. The law
  computes a 5-vector u, but only τ = (τ_r, τ_l) can be applied: we take τ = Bᵀ u (rows
  4–5 of u, the least-squares solution of B τ = u since BᵀB = I). Rows 1–3 of u are
  discarded; the controllers report their norm (the cost of this choice; docs/PAPER.md
  item 7).
* ``minimal``: the two wheel angles, M = M̄ = Sᵀ M S (constant), H = H̄, u = τ exactly.
  The law then tracks the wheel angles of a kinematically consistent reference; the pose
  is not fed back (drift of the pose is not corrected).

The pieces the laws share: the error dynamics (18)–(20) and the switching term (22),
(24)/(25) (``common``), the time-delay estimate (16)–(17) (``tde``, TDC and TDROC), the
nominal model's Ĥ (``model_based``, ROC and ASMC), and the configuration fields of each
piece (``fields``). The laws: ``tdc``, ``tdroc``, ``roc``, ``asmc``, ``pi``.

This package's namespace is the public one: other modules import from here.
"""

from modeling.controllers.asmc import ASMC, asmc_adaptation, asmc_law
from modeling.controllers.common import (
    DISTRIBUTED_SWITCHING_MAX_SIZE,
    Law,
    LawSymbols,
    law_symbols,
    lyapunov_p,
    nominal_acceleration,
    sliding_variable,
    switching_direction,
)
from modeling.controllers.declaration import (
    ControllerSpec,
    Estimate,
    Gain,
    Kernel,
    KernelArg,
    LawState,
)
from modeling.controllers.fields import BASE_CHECKS, SHARED_FIELDS, Check, ConfigField
from modeling.controllers.model import FORMULATIONS, ControlModel, Formulation, control_model
from modeling.controllers.model_based import model_law
from modeling.controllers.pi import PI, wheel_pi_law
from modeling.controllers.registry import CONTROLLERS, REGISTRY, controller, kernel
from modeling.controllers.roc import ROC, roc_law
from modeling.controllers.tdc import TDC
from modeling.controllers.tde import (
    TdeSymbols,
    in_trig,
    mass_angles,
    tde_estimate,
    tde_law,
    trig_symbols,
)
from modeling.controllers.tdroc import (
    ADJUGATE_NORM_MAX_SIZE,
    TDROC,
    heading_rotation,
    mass_inverse_norm,
    omega_difference_norm,
    rotation_residual,
    tdroc_gain,
    tdroc_weighted_gain,
)

__all__ = [
    "ADJUGATE_NORM_MAX_SIZE", "ASMC", "BASE_CHECKS", "CONTROLLERS",
    "DISTRIBUTED_SWITCHING_MAX_SIZE", "FORMULATIONS", "PI", "REGISTRY", "ROC",
    "SHARED_FIELDS", "TDC", "TDROC", "Check", "ConfigField", "ControlModel", "ControllerSpec",
    "Estimate", "Formulation", "Gain", "Kernel", "KernelArg", "Law", "LawState",
    "LawSymbols", "TdeSymbols", "asmc_adaptation", "asmc_law", "control_model", "controller",
    "heading_rotation", "in_trig", "kernel", "law_symbols", "lyapunov_p", "mass_angles",
    "mass_inverse_norm", "model_law", "nominal_acceleration", "omega_difference_norm",
    "roc_law", "rotation_residual", "sliding_variable", "switching_direction",
    "tde_estimate", "tde_law", "tdroc_gain", "tdroc_weighted_gain", "trig_symbols",
    "wheel_pi_law",
]
