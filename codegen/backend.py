"""What every code-generation backend is given, and what it gives back.

The driver (:mod:`codegen.generate`) derives a robot once and hands the same
:class:`RobotTarget` to every backend listed in :mod:`codegen.backends` (the registry);
it names none of them. A backend is any object satisfying :class:`Backend`: a ``name``,
the ``folder`` of ``generated/[<robot>/]`` its files go to, and ``render(target)``
returning ``{path relative to folder: text or bytes}``. Adding a backend is its own
package plus one line in the registry.

Every function reaches every backend in one shared intermediate form,
:class:`FunctionIR`: the :class:`~codegen.spec.FunctionSpec`, its common-subexpression
elimination (:func:`codegen.cse.cse_function`) and its operation count, computed once per
function per robot by :func:`function_ir`. Backends print from the IR; none runs CSE.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Protocol, runtime_checkable

from codegen import cse
from codegen.cse import CseResult, OpCount
from codegen.prepare import PreparedForm, prepared_form
from codegen.shared import SharedCall, share
from codegen.spec import FunctionSpec

if TYPE_CHECKING:
    from codegen.controller_layout import ControllerLayout
    from modeling.controllers import ControllerSpec
    from modeling.robot_file import Robot
    from modeling.robot_model import RobotModel


@dataclass(frozen=True, eq=False)
class FunctionIR:
    """One generated function as every backend receives it (compared by identity).

    ``cse``: the CSE of ``spec.checked_spec()``, i.e. the spec's outputs followed, for a
    spec with guards, by the guard conditions as a trailing output ``guard_`` (what the C
    and Python printers print, and what ``ops`` counts).
    ``plain``: the CSE of the spec's outputs alone, for a backend that has no guards
    (CasADi), without the shared reciprocals (CasADi's C divides as its graph says); the
    same object as ``cse`` when the spec has no guards.
    ``ops``: ``count_ops(cse)``, the "operations after CSE" every function documents.
    ``prepared``: for a spec with ``prepared``, ``cse`` split at the parameters (what a
    prepare-parameters API evaluates once, and the per-call rest); else None.
    """

    spec: FunctionSpec
    cse: CseResult
    plain: CseResult
    ops: OpCount
    prepared: PreparedForm | None = None
    # a backend that can call a module-level helper: this function's share of its group's
    # quantities (``codegen.shared``); ``cse`` above is still the whole function
    shared: SharedCall | None = None

    @property
    def name(self) -> str:
        return self.spec.name


def function_ir(spec: FunctionSpec) -> FunctionIR:
    """The shared form of ``spec`` (CSE once for its checked form, and once more for its
    outputs alone if it has guards)."""
    checked = cse.cse_function(spec.checked_spec(), reciprocals=True)
    plain = cse.cse_function(spec) if spec.guards else checked
    split = prepared_form(checked, spec) if spec.prepared else None
    return FunctionIR(spec, checked, plain, cse.count_ops(checked), split)


def with_shared(functions: tuple[FunctionIR, ...]) -> tuple[FunctionIR, ...]:
    """``functions`` with each group named by ``FunctionSpec.shares`` given its call of the
    group's helper (``codegen.shared``), in the order of their first member."""
    groups: dict[str, list[FunctionIR]] = {}
    for f in functions:
        if f.spec.shares:
            groups.setdefault(f.spec.shares, []).append(f)
    calls: dict[str, SharedCall] = {}
    for name, members in groups.items():
        _, group_calls = share([f.spec for f in members], name)
        calls.update({f.name: c for f, c in zip(members, group_calls, strict=True)})
    return tuple(replace(f, shared=calls[f.name]) if f.name in calls else f
                 for f in functions)


@dataclass(frozen=True)
class Module:
    """A group of functions generated together (``<prefix>_model``, ``_laws``, ``_plant``):
    one C ``.h``/``.c`` pair, one Python module. ``source`` names what they come from."""

    name: str
    functions: tuple[FunctionIR, ...]
    source: str

    @property
    def specs(self) -> tuple[FunctionSpec, ...]:
        return tuple(f.spec for f in self.functions)


@dataclass(frozen=True, eq=False)
class RobotTarget:
    """Everything a backend may read about one robot.

    ``model``: the derived robot (:class:`~modeling.robot_model.RobotModel`); ``robot``:
    the robot file's numbers (defaults written into the generated code); ``layout``: what
    the controller templates need; ``modules``: the generated functions in shared form;
    ``model_source`` / ``law_source``: what the model and the controller laws come from
    (for file preambles); ``controllers``: the controllers generated (the registry's,
    ``modeling.controllers.REGISTRY``), whose law kernels ``modules`` hold.
    """

    model: RobotModel
    robot: Robot
    layout: ControllerLayout
    modules: tuple[Module, ...]
    model_source: str
    law_source: str
    controllers: tuple[ControllerSpec, ...]

    def functions(self) -> Iterator[FunctionIR]:
        """Every generated function, module by module."""
        for module in self.modules:
            yield from module.functions

    def plant_values(self) -> dict[str, float]:
        """The simulated robot's parameters: the robot file's numbers, the model's
        defaults for plant-only parameters the file does not set."""
        given = self.robot.plant_values()
        return {
            p.key: float(given.get(p.key, self.model.values[p.key]))
            for p in self.model.plant_params
        }


@runtime_checkable
class Backend(Protocol):
    """A code-generation backend (see the module docstring)."""

    @property
    def name(self) -> str:
        """Short name, e.g. ``"c"``."""
        ...

    @property
    def folder(self) -> str:
        """The folder of ``generated/[<robot>/]`` the backend's files go to."""
        ...

    def render(self, target: RobotTarget) -> Mapping[str, str | bytes]:
        """``{path relative to folder: text (written as UTF-8) or bytes}`` for ``target``.
        Pure: the same target gives the same files whatever the hash seed."""
        ...
