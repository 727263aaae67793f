"""SymPy -> C99 expression printer for ``wmr_real_t`` code that builds in float or double.

Every floating literal goes through the literal macro (``WMR_LIT(0.5)`` is ``0.5f`` in the
float build), every math function through a ``WMR_`` macro (``sinf`` in the float build),
integer powers are products, ``x**(1/2)`` is ``WMR_SQRT`` (``wmr_norm<n>(x0, ...)`` for a sum of
squares, which cannot overflow), ``Piecewise`` is a ternary and
``Max``/``Min``/``Abs`` are ``WMR_FMAX``/``WMR_FMIN``/``WMR_FABS``. Structure is shared
with the Python printer and the op counter (:mod:`codegen.printer_base`).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence

import sympy as sp
from sympy.printing.c import C99CodePrinter

from codegen.backends.c.config import CConfig
from codegen.printer_base import ExpressionPrinterMixin, float_text


class CPrinter(ExpressionPrinterMixin, C99CodePrinter):
    """C99 printer over ``wmr_real_t``; symbols print as the names in ``symbol_names``."""

    def __init__(self, config: CConfig, symbol_names: Mapping[sp.Symbol, str],
                 bounded_trig: bool = False) -> None:
        super().__init__()
        self.config = config
        self.symbol_names = symbol_names
        self.ops = Counter()
        self.norms: set[int] = set()  # the n of every <prefix>norm<n> written (the types header's)
        self._macros = {m.name: m.arity for m in config.math_macros}
        self.bounded_trig = bounded_trig  # FunctionSpec.bounded_trig

    def lit(self, value: float) -> str:
        return f"{self.config.literal_macro}({float_text(value)})"

    def call(self, name: str, args: Sequence[str]) -> str:
        if self._macros.get(name) != len(args):
            raise ValueError(f"no {len(args)}-argument math macro for {name!r} in CConfig")
        bounded = "_BOUNDED" if self.bounded_trig and name in ("sin", "cos") else ""
        return f"{self.config.macro_prefix}{name.upper()}{bounded}({', '.join(args)})"

    def ternary(self, cond: str, if_true: str, if_false: str) -> str:
        return f"({cond} ? {if_true} : {if_false})"

    def infinity(self) -> str:
        return f"{self.config.macro_prefix}INF"

    def norm_call(self, args: Sequence[str]) -> str:
        # <prefix>_norm<n>, a static inline function of the types header (render_types)
        self.norms.add(len(args))
        return f"{self.config.prefix}norm{len(args)}({', '.join(args)})"
