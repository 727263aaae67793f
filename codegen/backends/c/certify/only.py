"""``--only``: re-certify some functions and steps of a robot and keep the others' stored
results (after a change to the printing of a few functions, their certificates alone, not
the robot's 10-16 minutes).

What a re-certified function or step reads from the others is taken from the stored
results, which must then be current (their printed-body hash matches the code printed
now; otherwise the command refuses and says which to name too): the enclosures of the
:data:`~codegen.backends.c.certify.boxes.DERIVED` inputs (P's entries from ``lyapunov_p``,
M-hat's from ``minimal_mhat``) that make the boxes, and, for a step, the bounds and
enclosures of the functions it combines (:meth:`~codegen.backends.c.certify.steps.Step.reads`).
``--only stale`` names every function whose stored result is missing or stale (its
printing, or its producer's for a composed one, changed since). A step is re-certified
when it is named (``tdroc/minimal``, or ``tdroc`` for each of its formulations) or when it
reads a re-certified function: its bound is made of theirs; a function that reads a
re-certified producer's derived inputs (its box is their enclosure), or is certified over
its image (:mod:`.compose`), when its producer is.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import sympy as sp

from codegen.backend import RobotTarget
from codegen.backends.c.backend import config_for
from codegen.backends.c.certify.bound import Certificate
from codegen.backends.c.certify.boxes import ENVELOPE, Interval, box_of, producers
from codegen.backends.c.certify.program import Program
from codegen.backends.c.certify.robot import derive, programs, robot_angles, robot_params
from codegen.backends.c.certify.steps import steps_of
from codegen.backends.c.lowering import function_context
from codegen.certify.header import body_hash

# the name ``--only`` takes for every function whose stored result is missing or stale
STALE = "stale"


class Refused(ValueError):
    """``--only`` cannot be honoured; the message is one line for the user."""


def split_names(values: Iterable[str]) -> list[str]:
    """``--only a,b --only c`` -> [a, b, c] (blanks dropped, order kept, no repeats)."""
    names = (n.strip() for v in values for n in v.split(","))
    return list(dict.fromkeys(n for n in names if n))


@dataclass(frozen=True)
class Plan:
    """What ``--only`` re-certifies for one robot and what it takes from the stored results."""

    functions: frozenset[str]
    steps: frozenset[str]  # Step.key, "controller/formulation"
    known: frozenset[str]  # the names given that belong to this robot
    derived: dict[str, Interval]  # stored enclosures of the DERIVED inputs not re-derived
    stored: dict[str, Certificate]  # stored certificates the re-certified steps read

    def __bool__(self) -> bool:
        return bool(self.functions or self.steps)


def stored_certificate(row: Mapping[str, Any]) -> Certificate:
    """A stored result row as the certificate it records."""
    outs = row["outputs"]
    return Certificate(
        function=row["function"], outputs=tuple(o["output"] for o in outs),
        bounds=tuple(float(o["bound"]) for o in outs),
        ranges=tuple((float(o["range"][0]), float(o["range"][1])) for o in outs),
        proved=bool(row["proved"]), reason=row["reason"], boxes=int(row["boxes"]),
        seconds=float(row["seconds"]), open_guards=tuple(row.get("open_guards", ())),
        divisors=tuple(row.get("divisors", ())))


def plan_only(robot: str, target: RobotTarget, stored: Mapping[str, Any] | None,
              names: Sequence[str]) -> Plan:
    """The plan for ``names`` (function names, step keys, controller names; those not of
    this robot are left out of :attr:`Plan.known`). Raises :class:`Refused` when the plan
    needs a stored result that is missing or stale."""
    irs = {ir.name: (ir, prog) for ir, prog in programs(target)}
    steps = {s.key: s for s in steps_of(target, irs)}
    rows = {r["function"]: r for r in (stored or {}).get("functions", [])}
    config = config_for(target.layout)

    def current(name: str) -> bool:
        row = rows.get(name)
        return row is not None and row["hash"] == body_hash(
            function_context(irs[name][0], config, "")["body"])

    functions = frozenset(n for n in names if n in irs)
    if STALE in names:  # every function with no stored result or a stale one
        functions |= {n for n in irs if not current(n) or (
            rows[n].get("composed") and not current(rows[n]["composed"]["function"]))}
    # the readers of a re-certified producer's derived inputs (their boxes are its output
    # enclosures), and a function certified over its producer's image (compose.py)
    functions |= {n for n, (_, prog) in irs.items() if producers(prog) & functions}
    functions |= {n for n, r in rows.items() if n in irs
                  and r.get("composed", {}).get("function") in functions}
    chosen = {k for n in names for k, s in steps.items() if n in (k, s.controller)}
    known = frozenset(n for n in names if n in irs or n == STALE) | {
        n for n in names for s in steps.values() if n in (s.key, s.controller)}
    chosen |= {k for k, s in steps.items() if s.reads(irs[s.law][1]) & functions}
    plan = Plan(functions, frozenset(chosen), frozenset(known), {}, {})
    if not plan:
        return plan
    # stored results read: the producers of the re-certified functions' derived inputs,
    # and every function a re-certified step combines, unless re-certified now
    reads = {p for n in functions for p in producers(irs[n][1])}
    reads |= {n for k in chosen for n in steps[k].reads(irs[steps[k].law][1])}
    reads -= functions
    for name in sorted(reads):
        row = rows.get(name)
        if row is None:
            raise Refused(f"{robot}: --only needs the stored certificate of {name}, and there "
                          f"is none: name {name} too (or run without --only)")
        if not current(name):
            raise Refused(f"{robot}: --only needs the stored certificate of {name}, which is "
                          f"stale (its printed code changed): name {name} too")
        plan.stored[name] = stored_certificate(row)
        derive(plan.derived, name, plan.stored[name].outputs, plan.stored[name].ranges)
    return plan


def step_inputs(target: RobotTarget, plan: Plan,
                certs: dict[str, tuple[Program, dict[sp.Symbol, Interval], Certificate]]
                ) -> None:
    """Add to ``certs`` (the re-certified functions') the program, box and stored
    certificate of every function the re-certified steps read and that was not re-certified,
    for :func:`~codegen.backends.c.certify.steps.step_certificates`."""
    ranges = dict(plan.derived)
    for name, (_, _, cert) in certs.items():
        derive(ranges, name, cert.outputs, cert.ranges)
    angles, params = robot_angles(target), robot_params(target, ENVELOPE)
    for ir, prog in programs(target):
        if ir.name in plan.stored and ir.name not in certs:
            certs[ir.name] = (prog, box_of(prog, angles, params, ranges, ENVELOPE),
                              plan.stored[ir.name])


def merged(stored: Mapping[str, Any], rows: Collection[Mapping[str, Any]],
           steps: Collection[Mapping[str, Any]]) -> dict[str, Any]:
    """``stored`` with the re-certified ``rows`` and ``steps`` in place of theirs (a new
    one appended); every other entry, and the whole-run fields, as stored."""
    new_rows = {r["function"]: r for r in rows}
    new_steps = {(s["controller"], s["formulation"]): s for s in steps}
    functions = [new_rows.pop(r["function"], r) for r in stored["functions"]]
    old_steps = [new_steps.pop((s["controller"], s["formulation"]), s) for s in stored["steps"]]
    return {**stored, "functions": functions + list(new_rows.values()),
            "steps": old_steps + list(new_steps.values())}
