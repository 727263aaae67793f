"""Certificates for every generated C function of one robot, in a dependency order."""

from __future__ import annotations

from collections.abc import Collection, Iterator, Mapping, Sequence

import sympy as sp

from codegen.backend import FunctionIR, RobotTarget
from codegen.backends.c.backend import config_for
from codegen.backends.c.certify.bound import Certificate, certify
from codegen.backends.c.certify.boxes import (
    DERIVED,
    ENVELOPE,
    Envelope,
    Interval,
    box_of,
    derived_key,
    input_errors,
    parameter_ranges,
    producers,
)
from codegen.backends.c.certify.compose import composed
from codegen.backends.c.certify.program import Program, program_of


def robot_angles(target: RobotTarget) -> tuple[bool, ...]:
    """Per coordinate of q: an angle (rad) or a position (m)."""
    return tuple(not n.startswith(("x", "y")) for n in target.model.coordinate_names)


def robot_params(target: RobotTarget, env: Envelope) -> dict[str, Interval]:
    """C field -> interval of every parameter (model and plant structs), and ``phys[i]`` ->
    that of the physical quantities the map from them reads."""
    values = target.model.values
    fields = {p.c_field: float(values[p.key]) for p in target.model.params}
    fields.update({p.c_field: float(values[p.key]) for p in target.model.plant_params
                   if p.key in values})
    ranges = parameter_ranges(fields, env)
    if target.model.physical is not None:  # plant_params_from_physical's inputs, phys[i]:
        # each physical quantity within the stated uncertainty of its nominal value; a
        # centre of mass or payload offset stated at 0 anywhere within ±payload_offset
        for i, q in enumerate(target.model.physical.inputs):
            a, b = q.nominal * (1 - env.uncertainty), q.nominal * (1 + env.uncertainty)
            ranges[f"phys[{i}]"] = ((min(a, b), max(a, b)) if q.nominal != 0.0 or q.unit != "m"
                                    else (-env.payload_offset, env.payload_offset))
    return ranges


def programs(target: RobotTarget) -> Iterator[tuple[FunctionIR, Program]]:
    """Each function's printed program; the producers of :data:`DERIVED` inputs first."""
    config = config_for(target.layout)
    items = [(f, program_of(f, config, m.name)) for m in target.modules for f in m.functions]
    first = {name for name, _ in DERIVED.values()}
    yield from sorted(items, key=lambda fp: fp[0].name not in first)


def derive(derived: dict[str, Interval], function: str, outputs: Sequence[str],
           ranges: Sequence[Interval]) -> None:
    """Record in ``derived`` the :data:`DERIVED` inputs ``function`` produces: each the hull
    of its outputs' enclosures."""
    for arg, (fn, stores) in DERIVED.items():
        if fn == function and all(s in outputs for s in stores):
            rng = [ranges[list(outputs).index(s)] for s in stores]
            derived[arg] = (min(r[0] for r in rng), max(r[1] for r in rng))


def certify_robot(target: RobotTarget, env: Envelope = ENVELOPE, seconds: float = 4.0,
                  only: Collection[str] | None = None, max_boxes: int = 4096,
                  derived: Mapping[str, Interval] | None = None,
                  ) -> Iterator[tuple[FunctionIR, Program, dict[sp.Symbol, Interval],
                                      Certificate]]:
    """Each function's program, box and certificate (``only``: those functions; the
    producers of :data:`DERIVED` inputs are certified too unless ``derived`` already gives
    their ranges, e.g. from stored results)."""
    angles = robot_angles(target)
    params = robot_params(target, env)
    ranges: dict[str, Interval] = dict(derived or {})
    items = list(programs(target))
    progs = {ir.name: prog for ir, prog in items}
    # the producers of the derived inputs the functions certified read, not given
    needed = {DERIVED[k][0] for ir, prog in items if only is None or ir.name in only
              for k in map(derived_key, prog.input_names.values()) if k and k not in ranges}
    for ir, prog in items:
        if only is not None and ir.name not in only and ir.name not in needed:
            continue
        box = box_of(prog, angles, params, ranges, env)
        cert = certify(prog, box, input_errors(prog), seconds=seconds, max_boxes=max_boxes)
        keys = {a: derived_key(a) for a in prog.input_names.values() if derived_key(a)}
        wiring = {a: DERIVED[k][1][0] for a, k in keys.items()}
        producer = producers(prog)
        if (not cert.proved and "divisor may be 0" in cert.reason and len(producer) == 1
                and len({a.split("[")[0] for a in wiring}) == 1  # one M-hat, not two q's
                and next(iter(producer)) in progs):
            # no bound over independent derived entries (singular M-hat in the box): over
            # the image of the producer instead (compose.py)
            first = progs[next(iter(producer))]
            prog = composed(first, prog, wiring)
            box = {**box_of(first, angles, params, ranges, env),
                   **{s: b for s, b in box.items() if s in prog.inputs}}
            cert = certify(prog, box, input_errors(prog), seconds=seconds,
                           max_boxes=max_boxes)
        derive(ranges, ir.name, cert.outputs, cert.ranges)
        if only is None or ir.name in only:
            yield ir, prog, dict(box), cert
