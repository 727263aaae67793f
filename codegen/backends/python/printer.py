"""SymPy -> Python expression printer over Python floats (``math`` functions, no NumPy
inside expressions). Structure is shared with the C printer and the op counter
(:mod:`codegen.printer_base`), so ``x**2`` is ``x*x`` here too.

Python raises where C returns NaN/inf: ``math.sqrt(-1.0)`` is a ``ValueError`` and
``1.0/0.0`` a ``ZeroDivisionError``.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence

import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from codegen.backends.python.config import PythonConfig
from codegen.printer_base import ExpressionPrinterMixin, float_text


class PyPrinter(ExpressionPrinterMixin, PythonCodePrinter):
    """Python printer; symbols print as the names in ``symbol_names``."""

    logic_and = " and "
    logic_or = " or "
    logic_not = "not "
    true_text = "True"
    false_text = "False"

    def __init__(self, config: PythonConfig, symbol_names: Mapping[sp.Symbol, str]) -> None:
        super().__init__()
        self.config = config
        self.symbol_names = symbol_names
        self.ops = Counter()

    def lit(self, value: float) -> str:
        return float_text(value)

    def call(self, name: str, args: Sequence[str]) -> str:
        try:
            function = self.config.functions[name]
        except KeyError:
            raise ValueError(f"no Python spelling for {name!r} in PythonConfig") from None
        return f"{function}({', '.join(args)})"

    def ternary(self, cond: str, if_true: str, if_false: str) -> str:
        return f"({if_true} if {cond} else {if_false})"

    def infinity(self) -> str:
        return "math.inf"

    def norm_call(self, args: Sequence[str]) -> str:
        return f"_norm({', '.join(args)})"  # the module's helper, as the C <prefix>_norm<n>
