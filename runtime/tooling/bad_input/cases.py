"""Every bad input tried on the generated C controllers, in the order of the table: bad
measurements and references, bad configuration fields, uninitialised states, NULL
pointers, and a torque beyond the limit; with the valid configuration they start from.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from runtime.bindings import cbuild
from runtime.bindings.generated import robot as generated_robot

# The paper robot's controllers, their formulations and fields (the registry, exported).
CONTROLLERS = tuple(str(c["name"]) for c in generated_robot.CONTROLLERS)
CONTROLLER_FORMULATIONS = {str(c["name"]): tuple(c["formulations"])
                           for c in generated_robot.CONTROLLERS}
CONTROLLER_FIELDS = {str(c["name"]): frozenset(f[0] for f in c["fields"])
                     for c in generated_robot.CONTROLLERS}
# Those whose state holds a window's ring (omega_head, omega_count): declared ``window``.
WINDOWED = tuple(str(c["name"]) for c in generated_robot.CONTROLLERS if c["window"])
FORMULATIONS = {"paper": 0, "minimal": 1}
INPUT_NAMES = ("q", "qdot", "q_des", "qdot_des", "qddot_des")
WARMUP = 5
SENTINEL = (111.0, -222.0)


def having(*fields: str) -> tuple[str, ...]:
    """The controllers whose configuration has every one of ``fields`` (a case that sets a
    field applies to those)."""
    return tuple(c for c in CONTROLLERS if set(fields) <= CONTROLLER_FIELDS[c])


DRISHTI = {"m": 36.0, "I": 5.72, "K": 0.34, "Iw": 0.07, "r": 0.096, "b": 0.414, "d": 0.12}
BASE: dict[str, Any] = {
    "k1": (4.0, 5.0, 6.0, 7.0, 8.0),
    "k2": (3.0, 3.5, 4.0, 4.5, 5.0),
    "q_pos": 1.5,
    "q_vel": 0.8,
    "h": 0.01,
    "tau_max": 200.0,
    "accel_estimator": 2,
    "rate_window": 0.005,
    "hold_gain": 0,
    "held_gain": 0.0,
    "eps": 0.05,
    "n": 4,
    "a": 0.8,
    "alpha": 0.3,
    "phi": 2.0,
    "gamma": 2.0,
    "gain0": 0.5,
    "kx": 1.0,
    "ky": 8.0,
    "ktheta": 4.0,
    "kp": 2.0,
    "ki": 2.0,
}
SATURATION_LIMIT = 0.5
ZERO_ERROR_STEPS = 30  # a zero-error streak at the smallest eps (issue 25's latch took 25+)


@dataclass(frozen=True)
class Case:
    """One bad input. ``row`` groups cases into one line of the table."""

    row: str
    # input | config | changed | state | corrupt | null | init-null | reset | saturate | zero-error
    kind: str
    expected: str
    applies: tuple[str, ...] = CONTROLLERS
    inputs: tuple[int, int, float] | None = None  # (which input, index, value)
    mutate: Mutation | None = None  # changes a copy of the configuration
    fill: bytes | None = None  # state cases: bytes the state is filled with (None: magic only)
    null_arg: int | None = None  # null cases: which argument of step is NULL
    flip: tuple[tuple[str, ...], int] | None = None  # corrupt cases: (state field path, bit)
    id: str = ""


class Mutation:
    """A change of a copy of the configuration, and the fields it touches (a case applies to
    the controllers that have them; "nominal": every controller)."""

    def __init__(self, fields: tuple[str, ...], change: Callable[[Any], None]) -> None:
        self.fields, self.change = fields, change

    def __call__(self, cfg: Any) -> None:
        self.change(cfg)


def _set(name: str, value: Any) -> Mutation:
    return Mutation((name,), lambda cfg: setattr(cfg, name, value))


def _set_item(name: str, index: int, value: float) -> Mutation:
    return Mutation((name,), lambda cfg: getattr(cfg, name).__setitem__(index, value))


def _negate(*where: tuple[str, int | None]) -> Mutation:
    """Negate fields (name, None) or vector entries (name, index): sign flips only."""
    def mutate(cfg: Any) -> None:
        for name, index in where:
            if index is None:
                setattr(cfg, name, -getattr(cfg, name))
            else:
                getattr(cfg, name)[index] = -getattr(cfg, name)[index]

    return Mutation(tuple(name for name, _ in where), mutate)


def _nominal(**changes: float) -> Mutation:
    return Mutation(("nominal",), lambda cfg: cbuild.fill_params(cfg.nominal, changes))


def max_window(lib: cbuild.CLibrary) -> int:
    """WMR_MAX_WINDOW, read from the C state (omega_ring has 2 WMR_MAX_WINDOW entries)."""
    fields = dict(lib.ffi.typeof("wmr_tdroc_state_t").fields)
    return int(fields["omega_ring"].type.length) // 2


def applies_to(mutate: Mutation) -> tuple[str, ...]:
    """The controllers a configuration case applies to: those with every field it sets."""
    return having(*(f for f in mutate.fields if f != "nominal"))


def cases(max_win: int) -> list[Case]:
    """Every bad input, in the order of the table."""
    out: list[Case] = []
    for which, label in enumerate(INPUT_NAMES):
        status = "WMR_ERR_BAD_MEASUREMENT" if which < 2 else "WMR_ERR_BAD_REFERENCE"
        bad_values = (
            ("NaN", math.nan),
            ("+Inf", math.inf),
            ("-Inf", -math.inf),
            ("1e9", 1e9),
            ("-1e9", -1e9),
        )
        for text, value in bad_values:
            for index in range(5):
                out.append(
                    Case(
                        f"`{label}[i]` = {text}",
                        "input",
                        status,
                        inputs=(which, index, value),
                        id=f"{label}[{index}]={text}",
                    )
                )
    k2m = DRISHTI["K"] ** 2 / DRISHTI["m"]
    config: list[tuple[str, str, Mutation]] = [
        ("`eps` = 0", "WMR_ERR_BAD_EPS", _set("eps", 0.0)),
        ("`eps` = -0.1", "WMR_ERR_BAD_EPS", _set("eps", -0.1)),
        ("`eps` = NaN", "WMR_ERR_BAD_EPS", _set("eps", math.nan)),
        ("`n` = 1", "WMR_ERR_BAD_WINDOW", _set("n", 1)),
        (
            f"`n` = WMR_MAX_WINDOW + 1 = {max_win + 1}",
            "WMR_ERR_BAD_WINDOW",
            _set("n", max_win + 1),
        ),
        ("`a` = 0", "WMR_ERR_BAD_DISCOUNT", _set("a", 0.0)),
        ("`a` = 1.5", "WMR_ERR_BAD_DISCOUNT", _set("a", 1.5)),
        ("`a` = NaN", "WMR_ERR_BAD_DISCOUNT", _set("a", math.nan)),
        ("`h` = 0", "WMR_ERR_BAD_SAMPLE_TIME", _set("h", 0.0)),
        ("`h` = -0.01", "WMR_ERR_BAD_SAMPLE_TIME", _set("h", -0.01)),
        ("`h` = NaN", "WMR_ERR_BAD_SAMPLE_TIME", _set("h", math.nan)),
        ("`h` = +Inf", "WMR_ERR_BAD_SAMPLE_TIME", _set("h", math.inf)),
        ("`k1[1]` = 0", "WMR_ERR_BAD_GAINS", _set_item("k1", 1, 0.0)),
        ("`k1[3]` = -4", "WMR_ERR_BAD_GAINS", _set_item("k1", 3, -4.0)),
        ("`k2[4]` = -5", "WMR_ERR_BAD_GAINS", _set_item("k2", 4, -5.0)),
        ("`k2[0]` = NaN", "WMR_ERR_BAD_GAINS", _set_item("k2", 0, math.nan)),
        ("Q: `q_pos` = 0", "WMR_ERR_BAD_GAINS", _set("q_pos", 0.0)),
        ("Q: `q_vel` = -1", "WMR_ERR_BAD_GAINS", _set("q_vel", -1.0)),
        ("nominal `m` = 0", "WMR_ERR_BAD_NOMINAL", _nominal(m=0.0)),
        ("nominal `m` = -36", "WMR_ERR_BAD_NOMINAL", _nominal(m=-36.0)),
        ("nominal `K` = NaN", "WMR_ERR_BAD_NOMINAL", _nominal(K=math.nan)),
        (
            "nominal `I` = K²/m (M-hat singular)",
            "WMR_ERR_BAD_NOMINAL",
            _nominal(I=k2m),
        ),
        (
            "nominal `I` = K²/(2m) (M-hat not positive definite)",
            "WMR_ERR_BAD_NOMINAL",
            _nominal(I=0.5 * k2m),
        ),
        ("nominal `Iw` = 0", "WMR_ERR_BAD_NOMINAL", _nominal(Iw=0.0)),
        ("nominal `b` = 0", "WMR_ERR_BAD_NOMINAL", _nominal(b=0.0)),
        ("nominal `r` = +Inf", "WMR_ERR_BAD_NOMINAL", _nominal(r=math.inf)),
        ("`tau_max` = 0", "WMR_ERR_BAD_TORQUE_LIMIT", _set("tau_max", 0.0)),
        ("`tau_max` = -5", "WMR_ERR_BAD_TORQUE_LIMIT", _set("tau_max", -5.0)),
        ("`tau_max` = NaN", "WMR_ERR_BAD_TORQUE_LIMIT", _set("tau_max", math.nan)),
        ("`tau_max` = +Inf", "WMR_ERR_BAD_TORQUE_LIMIT", _set("tau_max", math.inf)),
        ("`formulation` = 2", "WMR_ERR_BAD_FORMULATION", _set("formulation", 2)),
        ("`formulation` = -1", "WMR_ERR_BAD_FORMULATION", _set("formulation", -1)),
        ("`accel_estimator` = -1", "WMR_ERR_BAD_ESTIMATOR", _set("accel_estimator", -1)),
        ("`accel_estimator` = 3", "WMR_ERR_BAD_ESTIMATOR", _set("accel_estimator", 3)),
        ("`rate_window` = -0.001", "WMR_ERR_BAD_ESTIMATOR", _set("rate_window", -0.001)),
        ("`rate_window` > h", "WMR_ERR_BAD_ESTIMATOR", _set("rate_window", 0.02)),
        ("`rate_window` = NaN", "WMR_ERR_BAD_ESTIMATOR", _set("rate_window", math.nan)),
        ("TDROC `hold_gain` = 2", "WMR_ERR_BAD_HELD_GAIN", _set("hold_gain", 2)),
        ("TDROC `held_gain` = -1", "WMR_ERR_BAD_HELD_GAIN", _set("held_gain", -1.0)),
        (
            "TDROC `held_gain` = NaN",
            "WMR_ERR_BAD_HELD_GAIN",
            _set("held_gain", math.nan),
        ),
        ("ROC `alpha` = 1", "WMR_ERR_BAD_BOUNDS", _set("alpha", 1.0)),
        ("ROC `alpha` = -0.1", "WMR_ERR_BAD_BOUNDS", _set("alpha", -0.1)),
        ("ROC `phi` = -1", "WMR_ERR_BAD_BOUNDS", _set("phi", -1.0)),
        ("ROC `phi` = NaN", "WMR_ERR_BAD_BOUNDS", _set("phi", math.nan)),
        ("ASMC `gamma` = -1", "WMR_ERR_BAD_BOUNDS", _set("gamma", -1.0)),
        ("ASMC `gain0` = -1", "WMR_ERR_BAD_BOUNDS", _set("gain0", -1.0)),
        # Plausibility bounds (issue 13): accepted absurd values used to latch failure.
        ("`h` = 1.8e306 (> `WMR_H_MAX` = 1 s)", "WMR_ERR_BAD_SAMPLE_TIME", _set("h", 1.8e306)),
        ("`h` = 2 (> `WMR_H_MAX`)", "WMR_ERR_BAD_SAMPLE_TIME", _set("h", 2.0)),
        ("`h` = 1e-7 (< `WMR_H_MIN` = 1e-6 s)", "WMR_ERR_BAD_SAMPLE_TIME", _set("h", 1e-7)),
        ("`k1[2]` = 2e6 (> `WMR_GAIN_MAX` = 1e6)", "WMR_ERR_BAD_GAINS", _set_item("k1", 2, 2e6)),
        ("Q: `q_vel` = 1e7 (> `WMR_GAIN_MAX`)", "WMR_ERR_BAD_GAINS", _set("q_vel", 1e7)),
        ("`tau_max` = 1e7 (> `WMR_TORQUE_LIMIT_MAX` = 1e6)", "WMR_ERR_BAD_TORQUE_LIMIT",
         _set("tau_max", 1e7)),
        ("`eps` = 1e7 (> `WMR_GAIN_MAX`)", "WMR_ERR_BAD_EPS", _set("eps", 1e7)),
        ("TDROC `held_gain` = 1e7 (> `WMR_GAIN_MAX`)", "WMR_ERR_BAD_HELD_GAIN",
         _set("held_gain", 1e7)),
        ("ROC `phi` = 1e7 (> `WMR_GAIN_MAX`)", "WMR_ERR_BAD_BOUNDS", _set("phi", 1e7)),
        ("ASMC `gamma` = 1e7 (> `WMR_GAIN_MAX`)", "WMR_ERR_BAD_BOUNDS", _set("gamma", 1e7)),
        ("ASMC `gain0` = 1e7 (> `WMR_GAIN_MAX`)", "WMR_ERR_BAD_BOUNDS", _set("gain0", 1e7)),
        ("nominal `Iw` = 1e25 (> 1000 × max(0.07, 1))", "WMR_ERR_BAD_NOMINAL",
         _nominal(Iw=1e25)),
        ("nominal `m` = 1e6 (> 1000 × 36)", "WMR_ERR_BAD_NOMINAL", _nominal(m=1e6)),
        # Lower bounds (issue 25): an accepted eps of 2^-1074 made a step with exactly zero
        # error NaN ((k / eps) * 0); a wheel radius of 1e-30 m overflowed M-hat in float32.
        ("`eps` = 2^-1074 (< `WMR_GAIN_MIN` = 1e-6)", "WMR_ERR_BAD_EPS", _set("eps", 5e-324)),
        ("`k1[0]` = 1e-9 (< `WMR_GAIN_MIN`)", "WMR_ERR_BAD_GAINS", _set_item("k1", 0, 1e-9)),
        ("Q: `q_pos` = 1e-300 (< `WMR_GAIN_MIN`)", "WMR_ERR_BAD_GAINS", _set("q_pos", 1e-300)),
        ("nominal `r` = 1e-30 (< r / 1000)", "WMR_ERR_BAD_NOMINAL", _nominal(r=1e-30)),
        # Two sign flips after _init (issue 25): they cancelled in the old 32-bit fingerprint
        # (its bit 31 is the XOR of the words' bit 31), so the step used them unchecked.
        ("`k1[0]` and `k2[0]` negated after `_init` (two sign flips)", "WMR_ERR_BAD_GAINS",
         _negate(("k1", 0), ("k2", 0))),
        ("`tau_max` and `eps` negated after `_init` (two sign flips)",
         "WMR_ERR_BAD_TORQUE_LIMIT", _negate(("tau_max", None), ("eps", None))),
        # The wheel-velocity PI's gains.
        ("PI `kp` = 0", "WMR_ERR_BAD_GAINS", _set("kp", 0.0)),
        ("PI `ki` = -1", "WMR_ERR_BAD_GAINS", _set("ki", -1.0)),
        ("PI `kx` = NaN", "WMR_ERR_BAD_GAINS", _set("kx", math.nan)),
        ("PI `ky` = 1e7 (> `WMR_GAIN_MAX`)", "WMR_ERR_BAD_GAINS", _set("ky", 1e7)),
        ("PI `ktheta` = -Inf", "WMR_ERR_BAD_GAINS", _set("ktheta", -math.inf)),
    ]
    for row, status, mutate in config:
        out.append(Case(row, "config", status, applies_to(mutate), mutate=mutate, id=row))
    for row, mutate in (
        ("valid `k1[0]` = 4.5 after `_init`", _set_item("k1", 0, 4.5)),
        ("valid nominal `m` = 40 after `_init`", _nominal(m=40.0)),
        ("valid `tau_max` = 100 after `_init`", _set("tau_max", 100.0)),
        ("valid PI `kp` = 3 after `_init`", _set("kp", 3.0)),
    ):
        out.append(Case(row, "changed", "WMR_ERR_CONFIG_CHANGED", applies_to(mutate),
                        mutate=mutate, id=row))
    for row, fill in (
        ("state never initialised (zero-filled)", b"\x00"),
        ("state never initialised (filled with 0x5a)", b"\x5a"),
        ("initialised state with `magic` overwritten", None),
    ):
        out.append(Case(row, "state", "WMR_ERR_NOT_INITIALISED", fill=fill, id=row))
    # A corrupted state, magic intact (one flipped bit, issue 52): an index it holds out of
    # range is refused, as is its kept configuration, which no longer equals the caller's.
    for row, path, bit, status, applies in (
        ("TDROC `omega_head` bit 3 flipped (head 8..15; magic intact)", ("omega_head",), 3,
         "WMR_ERR_NOT_INITIALISED", WINDOWED),
        ("TDROC `omega_head` bit 31 flipped (head < 0; magic intact)", ("omega_head",), 31,
         "WMR_ERR_NOT_INITIALISED", WINDOWED),
        ("TDROC `omega_count` bit 4 flipped (count > WMR_MAX_WINDOW + 1; magic intact)",
         ("omega_count",), 4, "WMR_ERR_NOT_INITIALISED", WINDOWED),
        ("TDROC `omega_count` bit 31 flipped (count < 0; magic intact)", ("omega_count",), 31,
         "WMR_ERR_NOT_INITIALISED", WINDOWED),
        ("kept configuration: `tau_max`'s lowest bit flipped in the state (magic intact)",
         ("config", "tau_max"), 0, "WMR_ERR_CONFIG_CHANGED", CONTROLLERS),
        ("kept configuration: `formulation`'s bit 0 flipped in the state (magic intact)",
         ("config", "formulation"), 0, "WMR_ERR_CONFIG_CHANGED", CONTROLLERS),
    ):
        out.append(Case(row, "corrupt", status, applies, flip=(path, bit), id=row))
    step_args = ("state", "config", *INPUT_NAMES, "tau")
    for index, arg in enumerate(step_args):
        out.append(
            Case(
                f"`{arg}` = NULL in `_step`",
                "null",
                "WMR_ERR_NULL_POINTER",
                null_arg=index,
                id=f"step:{arg}=NULL",
            )
        )
    for index, arg in enumerate(("state", "config")):
        out.append(
            Case(
                f"`{arg}` = NULL in `_init`",
                "init-null",
                "WMR_ERR_NULL_POINTER",
                null_arg=index,
                id=f"init:{arg}=NULL",
            )
        )
    out.append(
        Case("`config` = NULL in `_check_config`", "init-null", "WMR_ERR_NULL_POINTER", id="check")
    )
    out.append(Case("`_reset` after 5 steps", "reset", "WMR_OK", id="reset"))
    out.append(Case("`state` = NULL in `_reset`", "init-null", "WMR_ERR_NULL_POINTER",
                    null_arg=2, id="reset:state=NULL"))
    out.append(
        Case(
            f"exactly zero tracking error for {ZERO_ERROR_STEPS} steps, `eps` = `WMR_GAIN_MIN` "
            "(TDROC: k-hat held at 1; ASMC: gain0 = 0.5)",
            "zero-error",
            "WMR_OK",
            id="zero-error",
        )
    )
    out.append(
        Case(
            f"torque beyond `tau_max` = {SATURATION_LIMIT}",
            "saturate",
            "WMR_WARN_SATURATED",
            id="saturate",
        )
    )
    return out
