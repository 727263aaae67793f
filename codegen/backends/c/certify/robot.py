"""Certificates for every generated C function of one robot, in a dependency order."""

from __future__ import annotations

from collections.abc import Collection, Iterator

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
    input_errors,
    parameter_ranges,
)
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


def certify_robot(target: RobotTarget, env: Envelope = ENVELOPE, seconds: float = 4.0,
                  only: Collection[str] | None = None, max_boxes: int = 4096
                  ) -> Iterator[tuple[FunctionIR, Program, dict[sp.Symbol, Interval],
                                      Certificate]]:
    """Each function's program, box and certificate."""
    angles = robot_angles(target)
    params = robot_params(target, env)
    derived: dict[str, Interval] = {}
    needed = {name for name, _ in DERIVED.values()}
    for ir, prog in programs(target):
        if only is not None and ir.name not in only and ir.name not in needed:
            continue
        box = box_of(prog, angles, params, derived, env)
        cert = certify(prog, box, input_errors(prog), seconds=seconds, max_boxes=max_boxes)
        for arg, (fn, stores) in DERIVED.items():
            if fn == ir.name and all(s in cert.outputs for s in stores):
                rng = [cert.ranges[cert.outputs.index(s)] for s in stores]
                derived[arg] = (min(r[0] for r in rng), max(r[1] for r in rng))
        if only is None or ir.name in only:
            yield ir, prog, dict(box), cert
