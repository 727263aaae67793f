"""A generated C function's body as a straight-line program, read from the printed text.

The certificate and the search follow the operations *as printed*: the statements
:func:`codegen.backends.c.lowering.function_context` lays out (the same :class:`Line`
list ``module.c.jinja`` spells), each expression parsed with C's precedence and left
associativity, so ``a + b + c`` is ``(a + b) + c`` exactly as a C99 compiler evaluates it
(``FLT_EVAL_METHOD`` 0, no contraction: the header's requirements). Nothing is re-derived
from SymPy: a change to the printer's operation order changes this program.

A program is a list of :class:`Node` in evaluation order (SSA: a name refers to the node
that defined it, so ``x*x`` of one local is recognisably a square), the input nodes (one
per symbol the function reads), the guards (``condition > 0`` or the function returns a
status) and the output nodes in store order.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import sympy as sp

from codegen.backend import FunctionIR
from codegen.backends.c.config import CConfig
from codegen.backends.c.lowering import access, c_local_names, function_context
from codegen.layout import input_slots

# Node operations. "in": an input; "lit": a literal (value = the printed double);
# arithmetic "neg" "add" "sub" "mul" "div"; "call": a math macro or norm (name);
# "cond": c ? a : b; comparisons "lt" "le" "gt" "ge" "eq" "ne"; "and" "or" "not".
COMPARISONS = {"<": "lt", "<=": "le", ">": "gt", ">=": "ge", "==": "eq", "!=": "ne"}


@dataclass(frozen=True)
class Node:
    op: str
    args: tuple[int, ...] = ()
    name: str = ""  # "in": the input's C local; "call": the function (sin, sqrt, norm ...)
    value: float = 0.0  # "lit": the printed double


@dataclass
class Program:
    """One function's printed evaluation: nodes in order, inputs, guards, outputs."""

    function: str
    nodes: list[Node] = field(default_factory=list)
    inputs: dict[sp.Symbol, int] = field(default_factory=dict)  # symbol -> "in" node
    input_names: dict[sp.Symbol, str] = field(default_factory=dict)  # symbol -> C access
    guards: list[tuple[int, str]] = field(default_factory=list)  # (node, status)
    outputs: list[tuple[str, int]] = field(default_factory=list)  # (C lvalue, node)
    # nonfinite checks (bit tests on inputs and results): certified by the no-overflow
    # proof rather than evaluated
    skipped_checks: int = 0
    # composed with the producer of its derived inputs (:mod:`.compose`): that function's
    # name, and consumer input access -> the producer's output lvalue it reads
    producer: str = ""
    wiring: dict[str, str] = field(default_factory=dict)

    def add(self, node: Node) -> int:
        self.nodes.append(node)
        return len(self.nodes) - 1


_TOKEN = re.compile(r"\s*(?:(?P<num>\d+\.?\d*(?:[eE][-+]?\d+)?)|(?P<id>[A-Za-z_]\w*)"
                    r"|(?P<op><=|>=|==|!=|&&|\|\||[-+*/()?:,<>!]))")


def _tokens(text: str) -> list[str]:
    out: list[str] = []
    pos = 0
    text = text.rstrip()
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if m is None or m.end() == pos:
            raise ValueError(f"cannot read C expression at {text[pos:pos + 30]!r}")
        out.append(m.group(m.lastgroup or "op"))
        pos = m.end()
    return out


class ExpressionParser:
    """Recursive descent over C's expression grammar (the subset the printer writes)."""

    def __init__(self, program: Program, scope: Mapping[str, int], config: CConfig) -> None:
        self.p = program
        self.scope = scope
        self.macro = config.macro_prefix
        self.prefix = config.prefix
        self.lit = config.literal_macro
        self.toks: list[str] = []
        self.i = 0

    def parse(self, text: str) -> int:
        self.toks, self.i = _tokens(text), 0
        node = self._ternary()
        if self.i != len(self.toks):
            raise ValueError(f"trailing text in {text!r}: {self.toks[self.i:]}")
        return node

    def _peek(self) -> str:
        return self.toks[self.i] if self.i < len(self.toks) else ""

    def _take(self, expected: str | None = None) -> str:
        tok = self._peek()
        if expected is not None and tok != expected:
            raise ValueError(f"expected {expected!r}, found {tok!r} in {' '.join(self.toks)}")
        self.i += 1
        return tok

    def _ternary(self) -> int:
        cond = self._or()
        if self._peek() != "?":
            return cond
        self._take("?")
        a = self._ternary()
        self._take(":")
        b = self._ternary()
        return self.p.add(Node("cond", (cond, a, b)))

    def _or(self) -> int:
        node = self._and()
        while self._peek() == "||":
            self._take()
            node = self.p.add(Node("or", (node, self._and())))
        return node

    def _and(self) -> int:
        node = self._rel()
        while self._peek() == "&&":
            self._take()
            node = self.p.add(Node("and", (node, self._rel())))
        return node

    def _rel(self) -> int:
        node = self._additive()
        while self._peek() in COMPARISONS:
            op = COMPARISONS[self._take()]
            node = self.p.add(Node(op, (node, self._additive())))
        return node

    def _additive(self) -> int:
        node = self._multiplicative()
        while self._peek() in ("+", "-"):
            op = "add" if self._take() == "+" else "sub"
            node = self.p.add(Node(op, (node, self._multiplicative())))
        return node

    def _multiplicative(self) -> int:
        node = self._unary()
        while self._peek() in ("*", "/"):
            op = "mul" if self._take() == "*" else "div"
            node = self.p.add(Node(op, (node, self._unary())))
        return node

    def _unary(self) -> int:
        tok = self._peek()
        if tok == "-":
            self._take()
            return self.p.add(Node("neg", (self._unary(),)))
        if tok == "!":
            self._take()
            return self.p.add(Node("not", (self._unary(),)))
        return self._primary()

    def _args(self) -> list[int]:
        self._take("(")
        args = [self._ternary()]
        while self._peek() == ",":
            self._take()
            args.append(self._ternary())
        self._take(")")
        return args

    def _primary(self) -> int:
        tok = self._take()
        if tok == "(":
            node = self._ternary()
            self._take(")")
            return node
        if tok == self.lit:
            self._take("(")
            text = self._take()
            self._take(")")
            return self.p.add(Node("lit", value=float(text)))
        if self._peek() == "(":
            return self._call(tok)
        if tok in self.scope:
            return self.scope[tok]
        raise ValueError(f"unknown name {tok!r}")

    def _call(self, tok: str) -> int:
        args = self._args()
        if tok.startswith(self.prefix + "norm"):
            # <prefix>norm<n>: the sum of squares left to right, then the square root
            # (the types header's; the scaled path is taken only when the sum overflows,
            # which the certificate proves it does not)
            total = self.p.add(Node("mul", (args[0], args[0])))
            for a in args[1:]:
                total = self.p.add(Node("add", (total, self.p.add(Node("mul", (a, a))))))
            return self.p.add(Node("call", (total,), name="sqrt"))
        if not tok.startswith(self.macro):
            raise ValueError(f"unknown function {tok!r}")
        name = tok[len(self.macro):].lower()
        return self.p.add(Node("call", tuple(args), name=name))


def program_of(ir: FunctionIR, config: CConfig, module: str = "") -> Program:
    """The printed body of ``ir``'s C function (its :func:`function_context`)."""
    spec = ir.spec
    ctx = function_context(ir, config, module)
    slots = input_slots(spec)
    names = c_local_names(spec, slots)
    by_access = {access(s.arg, s.field, s.index): s.symbol for s in slots}
    prog = Program(spec.name)
    scope: dict[str, int] = {}
    parser = ExpressionParser(prog, scope, config)
    body = ctx["body"]
    assert isinstance(body, list)
    results: dict[str, int] = {}
    for line in body:
        if line.kind in ("void", "call"):  # a call's arithmetic: the decls that follow
            continue
        if line.kind == "decl":
            symbol = by_access.get(line.value)
            if symbol is not None and names.get(symbol) == line.target:
                scope[line.target] = prog.add(Node("in", name=line.value))
                prog.inputs[symbol] = scope[line.target]
                prog.input_names[symbol] = line.value
            else:
                scope[line.target] = parser.parse(line.value)
                results[line.target] = scope[line.target]
        elif line.kind == "check":
            if "exp_carry" in line.value:
                prog.skipped_checks += 1
                continue
            m = re.fullmatch(r"!\((.*) > " + re.escape(config.literal_macro) + r"\(0\.0\)\)",
                             line.value)
            if m is None:
                raise ValueError(f"{spec.name}: unexpected check {line.value!r}")
            prog.guards.append((parser.parse(m.group(1)), line.status))
        elif line.kind == "store":
            prog.outputs.append((line.target, parser.parse(line.value)))
        else:
            raise ValueError(f"{spec.name}: unknown line kind {line.kind!r}")
    return prog



def parse_only(text: str, names: Sequence[str], config: CConfig) -> Program:
    """A one-expression program over inputs ``names`` (tests)."""
    prog = Program("expr")
    scope = {n: prog.add(Node("in", name=n)) for n in names}
    prog.inputs = {sp.Symbol(n): scope[n] for n in names}
    prog.input_names = {sp.Symbol(n): n for n in names}
    prog.outputs.append(("out", ExpressionParser(prog, scope, config).parse(text)))
    return prog
