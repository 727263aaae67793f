"""Options of the C99 backend."""

from __future__ import annotations

from dataclasses import dataclass, field

from codegen.spec import StatusCode  # the statuses are every backend's; re-exported here

__all__ = ["CConfig", "MathMacro", "StatusCode"]


@dataclass(frozen=True)
class MathMacro:
    """``WMR_<NAME>(args)``: ``<name>(args)`` in double, ``<name>f(args)`` in float."""

    name: str  # neutral name, also the C double function (sin, fmax, ...)
    arity: int


@dataclass(frozen=True)
class CConfig:
    """What the C backend emits; everything here is data the templates lay out.

    ``status_codes`` are the values of ``wmr_status_t`` (``WMR_OK = 0`` first); add codes
    here, not in a template. ``params_ctype`` is the struct type of ``"params"`` arguments
    whose ``Argument.ctype`` is empty.
    """

    prefix: str = "wmr_"
    types_header: str = "wmr_types.h"
    real_type: str = "wmr_real_t"
    status_type: str = "wmr_status_t"
    params_ctype: str = "wmr_params_t"
    float32_define: str = "WMR_FLOAT32"
    literal_macro: str = "WMR_LIT"
    status_codes: tuple[StatusCode, ...] = (StatusCode("WMR_OK", 0, "success"),)
    math_macros: tuple[MathMacro, ...] = field(
        default_factory=lambda: tuple(
            MathMacro(name, arity)
            for name, arity in (
                ("sin", 1),
                ("cos", 1),
                ("tan", 1),
                ("asin", 1),
                ("acos", 1),
                ("atan", 1),
                ("atan2", 2),
                ("sinh", 1),
                ("cosh", 1),
                ("tanh", 1),
                ("exp", 1),
                ("log", 1),
                ("sqrt", 1),
                ("pow", 2),
                ("fabs", 1),
                ("fmax", 2),
                ("fmin", 2),
            )
        )
    )

    # Integer constants for wmr_types.h: (name, value, doc).
    defines: tuple[tuple[str, str, str], ...] = ()

    @property
    def macro_prefix(self) -> str:
        """``WMR_`` for prefix ``wmr_``."""
        return self.prefix.upper()
