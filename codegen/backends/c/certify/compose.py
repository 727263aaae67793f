"""A function certified over the image of another: its derived inputs computed by their
producer (M-hat by ``minimal_mhat``) rather than taken from a box of independent entries.

The trailer's ``minimal_minv_norm_mhat`` divides by det(M-hat): over a box of M-hat's
entries each within its own enclosure the box holds singular matrices (M-hat[1] spans
[-0.19, 0.13] while M-hat[0] = M-hat[3] go down to 0.068), so no bound exists there. The
step only ever passes it the M-hat that ``minimal_mhat`` computed in float32 from q and the
parameters. :func:`composed` prints that as one program, the producer's nodes then the
consumer's with each derived input read from the producer's output node (the C stores
that float32 value and the consumer reads it back unchanged, so no rounding is added).
Its certificate is over the producer's box (angles and parameters) and the consumer's
other inputs, and bounds |float32 consumer(float32 M-hat(q)) - exact consumer(exact
M-hat(q))|: M-hat's own rounding included, what the step computes. :class:`ComposedExact`
is the search's exact reference for it: the producer's outputs at 113 bits fed, unrounded,
to the consumer's.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import mpmath
import sympy as sp

from codegen.backend import FunctionIR
from codegen.backends.c.certify.program import Node, Program
from codegen.backends.c.certify.search import Exact


def composed(producer: Program, consumer: Program, wiring: Mapping[str, str]) -> Program:
    """``consumer`` with each input whose C access is a key of ``wiring`` read from the
    ``producer``'s output with that C lvalue (``{"mhat[0]": "M[0]", ...}``); inputs of the
    same symbol shared. Named as the consumer."""
    out = Program(consumer.function, list(producer.nodes), dict(producer.inputs),
                  dict(producer.input_names), list(producer.guards),
                  skipped_checks=producer.skipped_checks + consumer.skipped_checks,
                  producer=producer.function, wiring=dict(wiring))
    stores = dict(producer.outputs)
    symbol_of = {n: s for s, n in consumer.inputs.items()}
    new: list[int] = []
    for idx, node in enumerate(consumer.nodes):
        sym = symbol_of.get(idx)
        if sym is not None and consumer.input_names[sym] in wiring:
            new.append(stores[wiring[consumer.input_names[sym]]])
        elif sym is not None and sym in out.inputs:
            new.append(out.inputs[sym])
        elif sym is not None:
            new.append(out.add(node))
            out.inputs[sym] = new[-1]
            out.input_names[sym] = consumer.input_names[sym]
        else:
            new.append(out.add(Node(node.op, tuple(new[a] for a in node.args), node.name,
                                    node.value)))
    out.guards += [(new[n], status) for n, status in consumer.guards]
    out.outputs = [(lvalue, new[n]) for lvalue, n in consumer.outputs]
    return out


class ComposedExact(Exact):
    """The exact outputs of :func:`composed`'s program at a point (its input symbols in
    order): the producer's, then the consumer's on them (mpmath, not rounded between)."""

    def __init__(self, producer: FunctionIR, consumer: FunctionIR, producer_prog: Program,
                 consumer_prog: Program, wiring: Mapping[str, str],
                 symbols: Sequence[sp.Symbol]) -> None:
        self.symbols = list(symbols)
        self._first = Exact(producer, [s for s in symbols if s in producer_prog.inputs])
        outs = [lv for lv, _ in producer_prog.outputs]
        by_access = {a: s for s, a in consumer_prog.input_names.items()}
        self._wired = {by_access[a]: outs.index(lv) for a, lv in wiring.items()
                       if a in by_access}
        self._second = Exact(consumer, [s for s in consumer_prog.inputs])

    def __call__(self, point: Sequence[float]) -> list[mpmath.mpf]:
        at = dict(zip(self.symbols, point, strict=True))
        first = self._first([at[s] for s in self._first.symbols])
        values = [first[self._wired[s]] if s in self._wired else at[s]
                  for s in self._second.symbols]
        return self._second(values)
