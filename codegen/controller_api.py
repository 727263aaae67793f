"""What the generated controller step functions are: names, statuses, configuration.

Shared by the C and Python controller templates so both APIs stay mirror images. The
arithmetic lives in the ``<prefix>_laws`` kernels (codegen.robot_functions); a step
function validates, keeps the history, calls the kernels, saturates and commits. Names and
sizes come from the robot's ``codegen.controller_layout.ControllerLayout``.
"""

from __future__ import annotations

from dataclasses import dataclass

from codegen.backends.c.config import StatusCode
from codegen.controller_layout import ControllerLayout, words
from codegen.robot_functions import MAX_WINDOW

# Input magnitudes beyond this are rejected as absurd (a lying sensor), not clipped.
MAX_ABS_INPUT = "1.0e6"


def status_codes(layout: ControllerLayout) -> tuple[StatusCode, ...]:
    """The values of ``<prefix>_status_t`` (names carry ``layout.PREFIX``)."""
    P = layout.PREFIX
    formulations = "PAPER or MINIMAL" if layout.paper else "MINIMAL (the only one generated)"
    return (
        StatusCode(f"{P}_OK", 0, "success"),
        StatusCode(f"{P}_WARN_SATURATED", 1, "success, but a torque was clipped to the limit"),
        StatusCode(f"{P}_ERR_NULL_POINTER", -1, "a pointer argument is NULL"),
        StatusCode(f"{P}_ERR_NONFINITE_INPUT", -2, "an input is NaN or infinite"),
        StatusCode(f"{P}_ERR_BAD_PARAMS", -3, "robot parameters do not give a valid model"),
        StatusCode(f"{P}_ERR_NONFINITE_OUTPUT", -4, "a result is not finite"),
        StatusCode(f"{P}_ERR_BAD_MEASUREMENT", -5, "q or qdot is NaN, infinite or absurdly large"),
        StatusCode(f"{P}_ERR_BAD_REFERENCE", -6, "a reference is NaN, infinite or absurdly large"),
        StatusCode(f"{P}_ERR_BAD_EPS", -7, "boundary layer eps <= 0 or not finite"),
        StatusCode(f"{P}_ERR_BAD_WINDOW", -8, f"window n outside 2..{P}_MAX_WINDOW"),
        StatusCode(f"{P}_ERR_BAD_DISCOUNT", -9, "discount a outside (0, 1]"),
        StatusCode(f"{P}_ERR_BAD_SAMPLE_TIME", -10, "h <= 0 or not finite"),
        StatusCode(f"{P}_ERR_BAD_GAINS", -11, "K1, K2 or Q not positive definite"),
        StatusCode(f"{P}_ERR_BAD_NOMINAL", -12, "nominal parameters give a singular M-hat"),
        StatusCode(f"{P}_ERR_BAD_TORQUE_LIMIT", -13, "torque limit <= 0 or NaN"),
        StatusCode(f"{P}_ERR_BAD_FORMULATION", -14, f"formulation is not {formulations}"),
        StatusCode(f"{P}_ERR_NOT_INITIALISED", -15, "state not initialised by _init"),
        StatusCode(
            f"{P}_ERR_BAD_BOUNDS", -16, "ROC alpha outside [0, 1) or phi < 0; ASMC gamma/gain < 0"
        ),
        StatusCode(
            f"{P}_ERR_BAD_ESTIMATOR",
            -17,
            "accel_estimator is not BACKWARD, CENTRAL or MATCHED, or rate_window is outside [0, h]",
        ),
        StatusCode(
            f"{P}_ERR_BAD_HELD_GAIN", -18, "TDROC hold_gain is not 0 or 1, or held_gain < 0"
        ),
    )


def defines(layout: ControllerLayout) -> tuple[tuple[str, str, str], ...]:
    """Integer constants of ``<prefix>_types.h``: (name, value, doc)."""
    P = layout.PREFIX
    paper_doc = f"the {words(layout.nq)} coordinates of (14), tau = B^T u"
    if not layout.paper:
        paper_doc += f": not generated for this robot ({P}_ERR_BAD_FORMULATION)"
    return (
        (f"{P}_FORMULATION_PAPER", "0", paper_doc),
        (f"{P}_FORMULATION_MINIMAL", "1", f"the {words(layout.nu)} wheel angles, tau = u"),
        (f"{P}_ACCEL_BACKWARD", "0", "qddot(t-h) = (qdot(t) - qdot(t-h))/h (default)"),
        (f"{P}_ACCEL_CENTRAL", "1", "qddot(t-h) = (qdot(t) - qdot(t-2h))/(2h)"),
        (
            f"{P}_ACCEL_MATCHED",
            "2",
            "backward quotient paired with (1-c) u(t-h) + c u(t-2h), c = rate_window/(2h)",
        ),
        (f"{P}_MAX_WINDOW", str(MAX_WINDOW), "largest TDROC window n (history size)"),
        (f"{P}_NQ", str(layout.nq), "generalised coordinates"),
        (f"{P}_STATE_MAGIC", layout.state_magic, "marks an initialised controller state"),
    )


# The paper's robot (importers written before robots were generic).


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
