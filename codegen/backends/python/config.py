"""Options of the NumPy/Python backend."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

# Neutral function name (codegen.printer_base) -> Python spelling. Scalar ``math`` calls
# are several times faster than NumPy ufuncs on Python floats; abs/max/min are builtins.
DEFAULT_FUNCTIONS: Mapping[str, str] = {
    "sin": "math.sin",
    "cos": "math.cos",
    "tan": "math.tan",
    "asin": "math.asin",
    "acos": "math.acos",
    "atan": "math.atan",
    "atan2": "math.atan2",
    "sinh": "math.sinh",
    "cosh": "math.cosh",
    "tanh": "math.tanh",
    "exp": "math.exp",
    "log": "math.log",
    "sqrt": "math.sqrt",
    "pow": "math.pow",
    "fabs": "abs",
    "fmax": "max",
    "fmin": "min",
}


@dataclass(frozen=True)
class PythonConfig:
    """What the Python backend emits."""

    functions: Mapping[str, str] = field(default_factory=lambda: dict(DEFAULT_FUNCTIONS))
    # Names the generated module itself defines or imports; locals must avoid them.
    reserved_names: tuple[str, ...] = (
        "math",
        "np",
        "Any",
        "Mapping",
        "ArrayLike",
        "NDArray",
        "annotations",
        "abs",
        "max",
        "min",
        "float",
    )
