"""Which controller steps have a run-time check of their float32 certificate's conditions,
and its name: shared by the C backend (``codegen.backends.c.certify.gate``, which renders
it with the certifier's boxes) and the reports (MODEL.md, docs/FLOAT32.md), which name it
in the steps' rows. Imports no backend, so the generator may import it."""

from __future__ import annotations

from modeling.controllers import REGISTRY, ControllerSpec


def has_check(info: ControllerSpec) -> bool:
    """A step whose torque bound is conditional on what the step produces: (25)'s window
    gain (TDROC) or a gain the law adapts (ASMC)."""
    return bool(info.window or info.adaptive)


def check_function(prefix: str, controller: str) -> str:
    """The C function that checks a step's conditions (the Python mirror's method is
    ``within_certificate``)."""
    return f"{prefix}_{controller}_within_certificate"


def checked_by(prefix: str, controller: str) -> str:
    """"checked by `<function>`" for a step row of a controller with a check, else ""."""
    info = next((c for c in REGISTRY if c.name == controller), None)
    return (f"run-time check: `{check_function(prefix, controller)}`, called after the step"
            if info is not None and has_check(info) else "")
