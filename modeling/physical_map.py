"""The map from a described robot's physical quantities to its model's base parameters.

A bodies-and-wheels robot's generated model takes base inertial parameters β
(``modeling.base_parameters``: the combinations of masses, inertias and centre-of-mass
offsets that its kinetic energy depends on), each a polynomial in the physical quantities
of the description. An uncertainty stated in the robot's own terms (each body's mass, yaw
inertia, centre of mass; a payload on the root body) reaches the model through this map:

    β_loaded(p) = payload_relations(β(p); m_L, x_L, y_L)

with β(p) the base parameters' expressions of the same reduction the generated model
uses (``modeling.robot_model.described_model``) and the payload's relations read off the
loaded robot's kinetic energy there. The wheel radii are kinematic (the constraints (6)–(8)
depend on them) and are not inputs: the map leaves them to the robot's own values.

Structure (checked by :func:`physical_map`, relied on by the bounds of
``runtime.bindings.physical_bounds``): every output is a polynomial of degree at most one
in each mass and inertia and at most two in each centre-of-mass coordinate (m c², from
½ m |v_com|²), so it is affine in the masses and inertias for fixed centres of mass but
not multilinear in a centre-of-mass coordinate. The generated robot.py carries each
polynomial's terms (``PHYSICAL_TERMS``) for an interval enclosure of its range.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

# The payload's inputs, named for the runtime: modeling.robot_model.PAYLOAD's m_L, x_L, y_L.
PAYLOAD_KEYS = ("payload_mass", "payload_x", "payload_y")
# Highest power of one input in any output: a mass or inertia appears linearly, a
# centre-of-mass (or payload position) coordinate at most squared.
MAX_DEGREE = {"mass": 1, "yaw_inertia": 1, "spin_inertia": 1, "diameter_inertia": 1,
              "com_x": 2, "com_y": 2, "payload_mass": 1, "payload_x": 2, "payload_y": 2}


@dataclass(frozen=True)
class PhysicalQuantity:
    """One input of the map: its key (``mass_cart``, ``com_x_cart``, ``payload_mass`` …),
    the symbol the derivation uses, its nominal value, its unit and what it is."""

    key: str
    symbol: sp.Symbol
    nominal: float
    unit: str
    doc: str


@dataclass(frozen=True)
class PhysicalMap:
    """Inputs (physical quantities, payload last), outputs (plant parameter keys) and each
    output's polynomial in the inputs' symbols."""

    inputs: tuple[PhysicalQuantity, ...]
    outputs: tuple[str, ...]
    exprs: tuple[sp.Expr, ...]

    def terms(self) -> dict[str, tuple[tuple[float, tuple[tuple[int, int], ...]], ...]]:
        """Each output's polynomial as (coefficient, ((input index, power), …)) terms."""
        symbols = [q.symbol for q in self.inputs]
        out = {}
        for key, expr in zip(self.outputs, self.exprs, strict=True):
            poly = sp.Poly(expr, *symbols)
            out[key] = tuple(
                (float(coeff), tuple((i, int(e)) for i, e in enumerate(powers) if e))
                for powers, coeff in sorted(poly.terms())
            )
        return out


_BODY_FIELDS = (("mass", "kg", "mass"), ("yaw_inertia", "kg m^2", "yaw inertia about its "
                "centre of mass"))
_WHEEL_FIELDS = (("mass", "kg", "mass"), ("spin_inertia", "kg m^2", "spin inertia"),
                 ("diameter_inertia", "kg m^2", "diameter inertia"))


def _kind(key: str) -> str:
    for stem in MAX_DEGREE:
        if key.startswith(stem):
            return stem
    raise ValueError(f"physical quantity '{key}' of no known kind")


def physical_inputs(sym: object, payload: tuple[sp.Symbol, sp.Symbol, sp.Symbol]
                    ) -> tuple[PhysicalQuantity, ...]:
    """The inputs of a symbolised description (``modeling.description.symbolize``), in
    description order: each body's mass, yaw inertia, centre of mass (x, y), each wheel's
    mass, spin and diameter inertia, then the payload on the root. A field given as an
    expression shared with another (not a symbol of its own) is not an input."""
    values = sym.values  # type: ignore[attr-defined]
    out: list[PhysicalQuantity] = []
    seen: set[sp.Symbol] = set()

    def add(value: object, unit: str, doc: str) -> None:
        if isinstance(value, sp.Symbol) and value not in seen and value in values:
            seen.add(value)
            out.append(PhysicalQuantity(str(value), value, float(values[value]), unit, doc))

    for b in sym.bodies:  # type: ignore[attr-defined]
        for name, unit, what in _BODY_FIELDS:
            add(getattr(b, name), unit, f"body '{b.name}': {what}")
        add(b.com[0], "m", f"body '{b.name}': centre of mass, x in its frame")
        add(b.com[1], "m", f"body '{b.name}': centre of mass, y in its frame")
    for w in sym.wheels:  # type: ignore[attr-defined]
        for name, unit, what in _WHEEL_FIELDS:
            add(getattr(w, name), unit, f"wheel '{w.name}': {what}")
    root = sym.bodies[0].name  # type: ignore[attr-defined]
    docs = (("kg", f"payload on '{root}': mass"),
            ("m", f"payload on '{root}': x in its frame"),
            ("m", f"payload on '{root}': y in its frame"))
    for key, symbol, (unit, doc) in zip(PAYLOAD_KEYS, payload, docs, strict=True):
        out.append(PhysicalQuantity(key, symbol, 0.0, unit, doc))
    return tuple(out)


def physical_map(sym: object, base: dict[sp.Symbol, sp.Expr],
                 payload_relations: dict[sp.Symbol, sp.Expr],
                 payload: tuple[sp.Symbol, sp.Symbol, sp.Symbol],
                 outputs: tuple[sp.Symbol, ...]) -> PhysicalMap:
    """The map of a described robot: ``base`` is each base parameter's expression in the
    physical symbols (``BaseReduction.relations``), ``payload_relations`` each plant
    parameter of the loaded robot in the unloaded one's and the payload, ``outputs`` the
    base parameters in the plant table's order. Raises ``ValueError`` if an output depends
    on a symbol that is not an input, or breaks the degree structure of the module
    docstring."""
    inputs = physical_inputs(sym, payload)
    symbols = {q.symbol for q in inputs}
    exprs = []
    for b in outputs:
        expr = sp.expand(payload_relations.get(b, b).subs(base, simultaneous=True))
        stray = expr.free_symbols - symbols
        if stray:
            raise ValueError(f"base parameter {b} depends on {', '.join(map(str, stray))}, "
                             "which is not a physical quantity of the description")
        for q in inputs:
            if sp.degree(expr, q.symbol) > MAX_DEGREE[_kind(q.key)]:
                raise ValueError(f"base parameter {b} has degree {sp.degree(expr, q.symbol)} "
                                 f"in {q.key}, above the derivation's "
                                 f"{MAX_DEGREE[_kind(q.key)]}")
        exprs.append(expr)
    return PhysicalMap(inputs, tuple(str(b) for b in outputs), tuple(exprs))
