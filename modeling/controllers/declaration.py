"""What a control law is, as typed declarations: the facts codegen builds a controller from.

A law (:class:`ControllerSpec`) says what it estimates the model's unknown part H with
(:class:`Estimate`), which gain its switching term has, if any (:class:`Gain`), whether it
has the error dynamics (18)-(20), what else it keeps in the state (:class:`LawState`), the
configuration fields only it has, and its kernel (the law itself, :class:`Kernel`). Its
whole configuration, the order the fields are validated in, and every feature switch of the
C and Python step templates (``tde``, ``switching``, ``window``, ...) are derived here from
those declarations; ``codegen.controller_api`` derives ``<prefix>_field_t`` and the Python
mirror's ``Config`` from the registry's fields. A new configuration field is one
:class:`~modeling.controllers.fields.ConfigField` in the law's ``own_fields``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum

import sympy as sp

from modeling.controllers.common import LawSymbols
from modeling.controllers.fields import (
    ADAPTIVE_FIELDS,
    BOUNDS_FIELDS,
    ERROR_DYNAMICS_FIELDS,
    FORMULATION_FIELD,
    H_FIELD,
    HOLD_FIELDS,
    SWITCHING_FIELDS,
    TAU_MAX_FIELD,
    TDE_FIELDS,
    WINDOW_FIELDS,
    ConfigField,
)
from modeling.controllers.model import FORMULATIONS, Formulation
from modeling.robot_model import RobotModel


class Estimate(Enum):
    """What the law takes for the part of the model it does not compute. ``TDE``: Ĥ1, the
    time-delay estimate (17), with a history in the state and the estimator's fields; the
    law then depends on q through M̂(q) only (its ``_trig``/``_mhat`` kernels). ``MODEL``:
    Ĥ(q, q̇) of the nominal model. ``NONE``: no model of the dynamics (a kinematic law,
    the PI baseline)."""

    TDE = "tde"
    MODEL = "model"
    NONE = "none"

    @property
    def fields(self) -> tuple[ConfigField, ...]:
        return TDE_FIELDS if self is Estimate.TDE else ()


class Gain(Enum):
    """The gain k of the switching term (22), (24)/(25), Δu_a = k s / max(‖s‖, ε), with the
    boundary layer ε; NONE: the law has no switching term."""

    NONE = "none"
    WINDOW = "window"  # k-hat of (25) over a window of past Omega's, kept in the state
    BOUNDS = "bounds"  # from uncertainty bounds alpha, phi in the configuration (ROC's rho)
    ADAPTIVE = "adaptive"  # adapted by the law, kept in the state and capped (ASMC)

    @property
    def fields(self) -> tuple[ConfigField, ...]:
        """Its configuration fields, in struct order."""
        return {Gain.NONE: (), Gain.WINDOW: (*WINDOW_FIELDS, *HOLD_FIELDS),
                Gain.BOUNDS: BOUNDS_FIELDS, Gain.ADAPTIVE: ADAPTIVE_FIELDS}[self]

    @property
    def checked(self) -> tuple[ConfigField, ...]:
        """Its fields in the order they are validated (the window's hold first)."""
        return (*HOLD_FIELDS, *WINDOW_FIELDS) if self is Gain.WINDOW else self.fields


class LawState(Enum):
    """What a law's kernel reads from the state and updates, besides what its estimate and
    gain keep (kernel arguments of that source, ``codegen.controller_api.STEP_SOURCES``)."""

    INTEGRAL = "integral"  # an integral per driven wheel


@dataclass(frozen=True)
class KernelArg:
    """One argument of a law kernel: its name (the kernel's parameter), what the step passes
    (``source``: ``codegen.controller_api.STEP_SOURCES``) and the symbols or expressions.
    A ``config`` argument's values are symbols named as the configuration fields the step
    passes (one field: a pointer to it; several: an array packed from them)."""

    name: str
    source: str
    values: tuple[sp.Expr, ...]
    doc: str = ""


@dataclass(frozen=True)
class Kernel:
    """A controller's law as one generated function of ``<prefix>_laws``: ``doc`` (after
    "(<formulation> formulation) "), the paper's equations, inputs after the nominal
    parameters, outputs."""

    doc: str
    equations: tuple[str, ...]
    inputs: tuple[KernelArg, ...]
    outputs: tuple[KernelArg, ...]
    definitions: tuple[tuple[sp.Symbol, sp.Expr], ...] = ()  # staged quantities it reads


def law_args(ls: LawSymbols, *names: str) -> tuple[KernelArg, ...]:
    """Kernel inputs that are law symbols, by name (the step's source has the same name)."""
    return tuple(KernelArg(n, n, tuple(getattr(ls, {"H1hat": "h1"}.get(n, n)))) for n in names)


# The error dynamics' inputs every law with them takes, as law_args names.
ERROR_DYNAMICS_ARGS = ("e", "edot", "qddot_des", "k1", "k2", "p12", "p22")


@dataclass(frozen=True)
class ControllerSpec:
    """A controller: identity, labels, what its law is, the fields only it has, its kernel.

    ``estimate``, ``gain``, ``error_dynamics`` (K1, K2, Q and P of (18)-(20), on the error
    e, ė of a formulation) and ``states`` are what the step functions are built from; the
    properties below (``tde``, ``switching``, ...) are the template switches, derived.
    ``own_fields``: configuration fields no shared piece has, after the others in struct
    order. ``formulations``: those it has where the robot does.
    """

    name: str
    label: str
    title: str
    equations: str
    kernel: Callable[[Formulation, RobotModel], Kernel]
    estimate: Estimate
    gain: Gain = Gain.NONE
    error_dynamics: bool = True
    states: tuple[LawState, ...] = ()
    own_fields: tuple[ConfigField, ...] = ()
    formulations: tuple[Formulation, ...] = FORMULATIONS

    def __post_init__(self) -> None:
        names = [f.name for f in self.fields]
        if len(set(names)) != len(names):
            raise ValueError(f"controller {self.name}: a configuration field twice: {names}")

    @property
    def fields(self) -> tuple[ConfigField, ...]:
        """``<prefix>_<ctrl>_config_t`` after ``nominal``, in struct order: formulation, the
        error dynamics', h, tau_max, the estimate's, the switching term's, the gain's, its
        own."""
        return (FORMULATION_FIELD, *(ERROR_DYNAMICS_FIELDS if self.error_dynamics else ()),
                H_FIELD, TAU_MAX_FIELD, *self.estimate.fields,
                *(SWITCHING_FIELDS if self.switching else ()), *self.gain.fields,
                *self.own_fields)

    @property
    def checks(self) -> tuple[str, ...]:
        """The fields in the order a configuration is validated (which status a
        configuration with several bad fields gets): formulation, h, the error dynamics'
        (together ``BASE_CHECKS``), tau_max, the switching term's, the estimate's, the
        gain's, its own."""
        order = (FORMULATION_FIELD, H_FIELD,
                 *(ERROR_DYNAMICS_FIELDS if self.error_dynamics else ()), TAU_MAX_FIELD,
                 *(SWITCHING_FIELDS if self.switching else ()), *self.estimate.fields,
                 *self.gain.checked, *self.own_fields)
        return tuple(f.name for f in order)

    def field(self, name: str) -> ConfigField:
        return next(f for f in self.fields if f.name == name)

    def formulations_of(self, model: RobotModel) -> tuple[Formulation, ...]:
        """The formulations generated for ``model``."""
        return tuple(f for f in model.formulations if f in self.formulations)

    # The template switches, each derived from the declaration above.
    @property
    def tde(self) -> bool:
        """H1hat from (17), with its history and estimator fields."""
        return self.estimate is Estimate.TDE

    @property
    def trig(self) -> bool:
        """The law has ``_trig``/``_mhat`` kernels taking sin/cos of q's angles or M-hat(q):
        with the TDE estimate it depends on q through M-hat only."""
        return self.estimate is Estimate.TDE

    @property
    def switching(self) -> bool:
        """A switching term with a boundary layer eps (the law returns s and ||s||)."""
        return self.gain is not Gain.NONE

    @property
    def window(self) -> bool:
        """k-hat of (25) over a window of past Omega's (the window in the state)."""
        return self.gain is Gain.WINDOW

    @property
    def bounds(self) -> bool:
        """Uncertainty bounds alpha, phi in the configuration."""
        return self.gain is Gain.BOUNDS

    @property
    def adaptive(self) -> bool:
        """A gain the law adapts, kept in the state and capped."""
        return self.gain is Gain.ADAPTIVE

    @property
    def integrator(self) -> bool:
        """An integral per driven wheel in the state, which the law updates."""
        return LawState.INTEGRAL in self.states
