"""What the generated controller step functions are: names, statuses, configuration.

Shared by the C and Python controller templates so both APIs stay mirror images. The
arithmetic lives in the ``wmr_laws`` kernels (codegen.wmr_functions); a step function
validates, keeps the history, calls the kernels, saturates and commits.
"""

from __future__ import annotations

from dataclasses import dataclass

from codegen.backends.c.config import StatusCode
from codegen.wmr_functions import MAX_WINDOW

# Input magnitudes beyond this are rejected as absurd (a lying sensor), not clipped.
MAX_ABS_INPUT = "1.0e6"

STATUS_CODES: tuple[StatusCode, ...] = (
    StatusCode("WMR_OK", 0, "success"),
    StatusCode("WMR_WARN_SATURATED", 1, "success, but a torque was clipped to the limit"),
    StatusCode("WMR_ERR_NULL_POINTER", -1, "a pointer argument is NULL"),
    StatusCode("WMR_ERR_NONFINITE_INPUT", -2, "an input is NaN or infinite"),
    StatusCode("WMR_ERR_BAD_PARAMS", -3, "robot parameters do not give a valid model"),
    StatusCode("WMR_ERR_NONFINITE_OUTPUT", -4, "a result is not finite"),
    StatusCode("WMR_ERR_BAD_MEASUREMENT", -5, "q or qdot is NaN, infinite or absurdly large"),
    StatusCode("WMR_ERR_BAD_REFERENCE", -6, "a reference is NaN, infinite or absurdly large"),
    StatusCode("WMR_ERR_BAD_EPS", -7, "boundary layer eps <= 0 or not finite"),
    StatusCode("WMR_ERR_BAD_WINDOW", -8, "window n outside 2..WMR_MAX_WINDOW"),
    StatusCode("WMR_ERR_BAD_DISCOUNT", -9, "discount a outside (0, 1]"),
    StatusCode("WMR_ERR_BAD_SAMPLE_TIME", -10, "h <= 0 or not finite"),
    StatusCode("WMR_ERR_BAD_GAINS", -11, "K1, K2 or Q not positive definite"),
    StatusCode("WMR_ERR_BAD_NOMINAL", -12, "nominal parameters give a singular M-hat"),
    StatusCode("WMR_ERR_BAD_TORQUE_LIMIT", -13, "torque limit <= 0 or NaN"),
    StatusCode("WMR_ERR_BAD_FORMULATION", -14, "formulation is not PAPER or MINIMAL"),
    StatusCode("WMR_ERR_NOT_INITIALISED", -15, "state not initialised by _init"),
    StatusCode(
        "WMR_ERR_BAD_BOUNDS", -16, "ROC alpha outside [0, 1) or phi < 0; ASMC gamma/gain < 0"
    ),
    StatusCode(
        "WMR_ERR_BAD_ESTIMATOR",
        -17,
        "accel_estimator is not BACKWARD, CENTRAL or MATCHED, or rate_window is outside [0, h]",
    ),
    StatusCode("WMR_ERR_BAD_HELD_GAIN", -18, "TDROC hold_gain is not 0 or 1, or held_gain < 0"),
)

DEFINES: tuple[tuple[str, str, str], ...] = (
    ("WMR_FORMULATION_PAPER", "0", "the five coordinates of (14), tau = B^T u"),
    ("WMR_FORMULATION_MINIMAL", "1", "the two wheel angles, tau = u"),
    ("WMR_ACCEL_BACKWARD", "0", "qddot(t-h) = (qdot(t) - qdot(t-h))/h (default)"),
    ("WMR_ACCEL_CENTRAL", "1", "qddot(t-h) = (qdot(t) - qdot(t-2h))/(2h)"),
    (
        "WMR_ACCEL_MATCHED",
        "2",
        "backward quotient paired with (1-c) u(t-h) + c u(t-2h), c = rate_window/(2h)",
    ),
    ("WMR_MAX_WINDOW", str(MAX_WINDOW), "largest TDROC window n (history size)"),
    ("WMR_NQ", "5", "generalised coordinates"),
    ("WMR_STATE_MAGIC", "0x574d52", "marks an initialised controller state"),
)


@dataclass(frozen=True)
class ControllerInfo:
    name: str
    title: str
    equations: str
    tde: bool  # H1hat from the time-delay estimate (17) (else the nominal model H-hat)
    switching: bool  # has a switching term and eps
    window: bool  # TDROC's history window n, a
    bounds: bool  # ROC's alpha, phi
    adaptive: bool  # ASMC's gamma, initial gain


CONTROLLERS: tuple[ControllerInfo, ...] = (
    ControllerInfo("tdc", "time-delay control", "(16)-(18)", True, False, False, False, False),
    ControllerInfo(
        "tdroc",
        "time-delayed robust optimal control",
        "(16)-(18), (22)-(25)",
        True,
        True,
        True,
        False,
        False,
    ),
    ControllerInfo(
        "roc",
        "robust control with predefined bounds",
        "(22), (24)",
        False,
        True,
        False,
        True,
        False,
    ),
    ControllerInfo(
        "asmc", "adaptive sliding-mode control", "(22), (24)", False, True, False, False, True
    ),
)
