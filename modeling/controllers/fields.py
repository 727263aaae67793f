"""A controller's configuration fields: what one is, and the ones the laws share.

A field of ``<prefix>_<ctrl>_config_t`` is declared once, as a :class:`ConfigField`; the C
struct member and its comment, the C and Python checks, the ``<prefix>_field_t`` entry an
error names it by, the Python mirror's ``Config`` member and default, and the runtime's
configuration builder (``source``) are all read from it. The fields below belong to the
pieces a law is made of (``modeling.controllers.declaration``): every law has
``BASE_FIELDS``, a law with the error dynamics (18)-(20) ``ERROR_DYNAMICS_FIELDS``, the
time-delay estimate ``TDE_FIELDS``, a switching term ``SWITCHING_FIELDS``, and each kind of
switching gain its own. A field only one law has is declared in that law's file.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Literal


class Check(StrEnum):
    """How the C and the Python mirror validate a field: its bounds. Each is written once
    in the C template (``controller.c.jinja``, ``check_field``) and once in the mirror
    (``controllers.py.jinja``, ``_FIELD_CHECKS``)."""

    FORMULATION = "formulation"  # a formulation the controller has for the robot
    SAMPLE_TIME = "sample_time"  # [H_MIN, H_MAX]
    TORQUE_LIMIT = "torque_limit"  # (0, TORQUE_LIMIT_MAX]
    GAIN = "gain"  # [GAIN_MIN, GAIN_MAX]
    NONNEGATIVE_GAIN = "nonnegative_gain"  # [0, GAIN_MAX]
    ESTIMATOR = "estimator"  # ACCEL_BACKWARD, ACCEL_CENTRAL or ACCEL_MATCHED
    RATE_WINDOW = "rate_window"  # [0, h]
    FLAG = "flag"  # 0 or 1
    WINDOW = "window"  # 2..MAX_WINDOW
    DISCOUNT = "discount"  # (0, 1]
    ALPHA = "alpha"  # [0, 1)


Kind = Literal["real", "int", "vector"]


@dataclass(frozen=True)
class ConfigField:
    """One field of ``<prefix>_<ctrl>_config_t`` (after ``nominal``).

    ``kind``: its C type, ``real`` (``<prefix>_real_t``), ``int``, or ``vector`` (one
    ``<prefix>_real_t`` per coordinate of q). ``check``: its bounds (:class:`Check`), a value
    outside them failing with status ``ERR_<status>``. ``unit``: its unit ("" when none).
    ``doc``: the struct comment, a format string over ``PRE`` (the C prefix in capitals),
    ``actuated_k1`` and ``formulations`` (the robot's). ``source``: where the runtime's
    configuration builder takes the value (``runtime`` knows each source;
    ``experiment.<section>.<field>`` reads an experiment field). ``default``: the Python
    mirror's default, a Python expression over the mirror's constants (``{FORMULATION}``:
    ``PAPER`` or ``MINIMAL``, the robot's first); a vector's is one entry's.
    ``field_id``: its number in ``<prefix>_field_t`` (which field an error is about; stable:
    a shipped field keeps its number); None appends it after the numbered ones, in
    registry order. ``about``: words after its name in that enumeration's comment."""

    name: str
    kind: Kind
    check: Check
    status: str
    unit: str
    doc: str
    source: str
    default: str
    field_id: int | None = None
    about: str = ""

    def __post_init__(self) -> None:
        if not self.name.isidentifier() or self.name != self.name.lower():
            raise ValueError(f"configuration field {self.name!r}: a lower-case identifier")

    def c_type(self, prefix: str) -> str:
        """The C type of one value (``<prefix>_real_t`` or ``int``)."""
        return "int" if self.kind == "int" else f"{prefix}_real_t"

    @property
    def python_type(self) -> str:
        """The annotation of the Python mirror's ``Config`` member."""
        return {"real": "float", "int": "int", "vector": "ArrayLike"}[self.kind]

    @property
    def detail_doc(self) -> str:
        """Its comment in ``<prefix>_field_t``: the name (with ``[index]`` for a vector)
        and ``about``."""
        text = f"{self.name}[index]" if self.kind == "vector" else self.name
        return f"{text} ({self.about})" if self.about else text


# Every law: formulation, then (after the error dynamics' fields, where it has them) h and
# tau_max.
FORMULATION_FIELD = ConfigField(
    "formulation", "int", Check.FORMULATION, "BAD_FORMULATION", "", "{formulations}",
    "formulation", "FORMULATION_{FORMULATION}", field_id=10)
H_FIELD = ConfigField("h", "real", Check.SAMPLE_TIME, "BAD_SAMPLE_TIME", "s",
                      "sample time [s], [H_MIN, H_MAX]", "experiment.controller.h", "0.1",
                      field_id=15)
TAU_MAX_FIELD = ConfigField(
    "tau_max", "real", Check.TORQUE_LIMIT, "BAD_TORQUE_LIMIT", "N m",
    "torque limit [N m], (0, TORQUE_LIMIT_MAX]; larger torques are clipped",
    "experiment.controller.tau_max", "50.0", field_id=16)
BASE_FIELDS = (FORMULATION_FIELD, H_FIELD, TAU_MAX_FIELD)

# The error dynamics (18)-(20): K1, K2 and Q (P follows).
K1_FIELD = ConfigField(
    "k1", "vector", Check.GAIN, "BAD_GAINS", "1/s^2",
    "diagonal of K1 (18), [GAIN_MIN, GAIN_MAX]; the minimal form uses {actuated_k1}",
    "experiment.controller.k1", "4.0", field_id=11)
K2_FIELD = ConfigField(
    "k2", "vector", Check.GAIN, "BAD_GAINS", "1/s",
    "diagonal of K2 (18), [GAIN_MIN, GAIN_MAX]", "experiment.controller.k2", "4.0",
    field_id=12)
Q_POS_FIELD = ConfigField(
    "q_pos", "real", Check.GAIN, "BAD_GAINS", "",
    "Q = diag(q_pos I, q_vel I) of the Lyapunov equation, [GAIN_MIN, GAIN_MAX]",
    "experiment.controller.q_pos", "1.0", field_id=13)
Q_VEL_FIELD = ConfigField("q_vel", "real", Check.GAIN, "BAD_GAINS", "", "",
                          "experiment.controller.q_vel", "1.0", field_id=14)
ERROR_DYNAMICS_FIELDS = (K1_FIELD, K2_FIELD, Q_POS_FIELD, Q_VEL_FIELD)

# The time-delay estimate (17): how qddot(t-h) is estimated.
ESTIMATOR_FIELD = ConfigField(
    "accel_estimator", "int", Check.ESTIMATOR, "BAD_ESTIMATOR", "",
    "qddot(t-h) for (17): {PRE}_ACCEL_BACKWARD, _CENTRAL or _MATCHED", "accel_estimator",
    "ACCEL_BACKWARD", field_id=17)
RATE_WINDOW_FIELD = ConfigField(
    "rate_window", "real", Check.RATE_WINDOW, "BAD_ESTIMATOR", "s",
    "span [s] over which qdot is measured, 0..h (MATCHED): 0 for a\n"
    "rate at the sample instant, h for encoder counts over h", "rate_window", "0.0",
    field_id=18)
TDE_FIELDS = (ESTIMATOR_FIELD, RATE_WINDOW_FIELD)

# A switching term (24)/(25): its boundary layer.
EPS_FIELD = ConfigField("eps", "real", Check.GAIN, "BAD_EPS", "",
                        "boundary layer of (24)/(25), [GAIN_MIN, GAIN_MAX]",
                        "experiment.controller.eps", "0.1", field_id=19)
SWITCHING_FIELDS = (EPS_FIELD,)

# The window gain k-hat of (25): the window, its discount, and the gain held instead.
N_FIELD = ConfigField("n", "int", Check.WINDOW, "BAD_WINDOW", "",
                      "window of past instants, 2..{PRE}_MAX_WINDOW", "experiment.controller.n",
                      "4", field_id=20)
A_FIELD = ConfigField("a", "real", Check.DISCOUNT, "BAD_DISCOUNT", "",
                      "discount, 0 < a <= 1; weights a^(i-1), normalised",
                      "experiment.controller.a", "0.9", field_id=21)
WINDOW_FIELDS = (N_FIELD, A_FIELD)
HOLD_GAIN_FIELD = ConfigField("hold_gain", "int", Check.FLAG, "BAD_HELD_GAIN", "",
                              "0: k-hat from (25); 1: k-hat held at held_gain", "hold_gain",
                              "0", field_id=22)
HELD_GAIN_FIELD = ConfigField("held_gain", "real", Check.NONNEGATIVE_GAIN, "BAD_HELD_GAIN", "",
                              "[0, GAIN_MAX], used when hold_gain = 1", "held_gain", "0.0",
                              field_id=23)
HOLD_FIELDS = (HOLD_GAIN_FIELD, HELD_GAIN_FIELD)

# The gain from predefined uncertainty bounds (ROC's rho).
ALPHA_FIELD = ConfigField("alpha", "real", Check.ALPHA, "BAD_BOUNDS", "",
                          "bound on ||M^-1 Mhat - I|| over the uncertainty box, [0, 1)",
                          "roc_bounds.alpha", "0.3", field_id=24)
PHI_FIELD = ConfigField("phi", "real", Check.NONNEGATIVE_GAIN, "BAD_BOUNDS", "",
                        "bound on ||M^-1 (H - Hhat)||, [0, GAIN_MAX]", "roc_bounds.phi", "1.0",
                        field_id=25)
BOUNDS_FIELDS = (ALPHA_FIELD, PHI_FIELD)

# The adapted gain (ASMC's k-hat): its rate and start.
GAMMA_FIELD = ConfigField("gamma", "real", Check.NONNEGATIVE_GAIN, "BAD_BOUNDS", "",
                          "adaptation rate of the switching gain, [0, GAIN_MAX]",
                          "experiment.controller.gamma", "1.0", field_id=26)
GAIN0_FIELD = ConfigField(
    "gain0", "real", Check.NONNEGATIVE_GAIN, "BAD_BOUNDS", "",
    "initial switching gain, [0, GAIN_MAX]; the gain is capped at GAIN_MAX", "zero", "0.0",
    field_id=27)
ADAPTIVE_FIELDS = (GAMMA_FIELD, GAIN0_FIELD)

# The shared fields in the order the Python mirror's Config lists them (a stable API: a
# shared field joins its piece's tuple above, and is listed here through it), before the
# fields of single laws.
SHARED_FIELDS = (FORMULATION_FIELD, *ERROR_DYNAMICS_FIELDS, H_FIELD, TAU_MAX_FIELD,
                 *TDE_FIELDS, *HOLD_FIELDS, *SWITCHING_FIELDS, *WINDOW_FIELDS, *BOUNDS_FIELDS,
                 *ADAPTIVE_FIELDS)

# What <prefix>_check_base_config checks, in its order (a law with the error dynamics).
BASE_CHECKS = tuple(f.name for f in (FORMULATION_FIELD, H_FIELD, *ERROR_DYNAMICS_FIELDS,
                                     TAU_MAX_FIELD))
