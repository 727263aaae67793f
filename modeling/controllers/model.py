"""The model a control law acts on: M̂(q), Ĥ(q, q̇) of one formulation at the nominal
parameters (the formulations are described in ``modeling.controllers``)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import Literal

import sympy as sp

from modeling.lagrange import ConstrainedSystem
from modeling.robot_model import RobotModel
from modeling.staged import Stage

Formulation = Literal["paper", "minimal"]
FORMULATIONS: tuple[Formulation, ...] = ("paper", "minimal")


@dataclass(frozen=True)
class ControlModel:
    """M̂(q), Ĥ(q, q̇) and Bᵀ-selection of one formulation at the nominal parameters.

    ``size`` is the number of controlled coordinates and ``rows`` their indices in q
    (all of q for the paper form; the actuated wheel angles for the minimal form).
    ``stage``: for a staged robot (``RobotModel.staged``), the quantities M̂ and Ĥ are
    written in (``modeling.staged``); a law's kernel evaluates the ones it reads.
    """

    formulation: Formulation
    size: int
    rows: tuple[int, ...]
    mass: sp.Matrix
    bias: sp.Matrix
    velocities: tuple[sp.Symbol, ...]
    system: ConstrainedSystem
    stage: Stage | None = None

    @property
    def mass_inverse(self) -> sp.Matrix:
        """M̂⁻¹ in closed form (by cofactors; derived on first use: only the paper
        formulation's ‖M̂⁻¹‖ reads it)."""
        if self.stage is not None:
            raise ValueError("a staged model has no closed-form M-hat inverse")
        if self.formulation == "paper":
            return self.system.reduced_mass_matrix_inverse
        return self.system.minimal_mass_matrix_inverse

    def definitions(self, exprs: list[sp.Expr]) -> tuple[tuple[sp.Symbol, sp.Expr], ...]:
        """The staged quantities ``exprs`` read (none for a closed-form model)."""
        return () if self.stage is None else self.stage.definitions_for(exprs)

    def depends_on(self, exprs: list[sp.Expr], symbols: tuple[sp.Symbol, ...]) -> bool:
        """Whether ``exprs`` depend on ``symbols``, through the staged quantities too."""
        wanted = set(symbols)
        return any(e.free_symbols & wanted
                   for e in [*exprs, *(d for _, d in self.definitions(exprs))])


def control_model(formulation: Formulation, model: RobotModel) -> ControlModel:
    """The model a controller uses. Paper: M̃, H̃ of (14); minimal: M̄, H̄ (Sᵀ M S form)."""
    return _control_model(formulation, model)


@cache
def _control_model(formulation: Formulation, model: RobotModel) -> ControlModel:
    s = model.system
    rates = tuple(model.qdot[i] for i in model.actuated)
    if formulation == "paper" and model.paper:
        return ControlModel(
            formulation,
            model.nq,
            tuple(range(model.nq)),
            s.reduced_mass_matrix,
            s.reduced_bias,
            rates,
            s,
        )
    if formulation == "minimal" and model.staged:
        stage = Stage("_c")
        staged = s.staged_minimal(stage, root_frame=True, positive=model.positive_symbols)
        return ControlModel(formulation, model.nu, model.actuated, staged.mass_matrix,
                            staged.bias, rates, s, stage)
    if formulation == "minimal":
        return ControlModel(
            formulation,
            model.nu,
            model.actuated,
            s.minimal_mass_matrix,
            s.minimal_bias,
            rates,
            s,
        )
    raise ValueError(
        f"formulation {formulation!r} is not available for robot '{model.name}' "
        f"(available: {', '.join(model.formulations)})"
    )
