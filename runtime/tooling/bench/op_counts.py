"""Operation counts of CasADi's SX graph for a function, by kind (add, mul, div, sin/cos,
sqrt, other), to compare with ours after CSE.
"""

from __future__ import annotations

from codegen.backends.casadi import to_casadi
from codegen.spec import FunctionSpec


def casadi_op_count(spec: FunctionSpec) -> dict[str, int]:
    import casadi as ca

    f = to_casadi(spec)
    names = {
        ca.OP_ADD: "add",
        ca.OP_SUB: "add",
        ca.OP_MUL: "mul",
        ca.OP_DIV: "div",
        ca.OP_SIN: "sin/cos",
        ca.OP_COS: "sin/cos",
        ca.OP_SQRT: "sqrt",
        ca.OP_SQ: "mul",
        ca.OP_NEG: "neg",
        ca.OP_FMAX: "other",
        ca.OP_FABS: "other",
        ca.OP_TWICE: "add",
        ca.OP_INV: "div",
        ca.OP_POW: "other",
        ca.OP_CONSTPOW: "other",
    }
    counts: dict[str, int] = {}
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        if op in names:
            counts[names[op]] = counts.get(names[op], 0) + 1
    counts.pop("neg", None)
    return counts
