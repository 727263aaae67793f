"""Sensor and actuator faults injected into the closed loop of any robot (``runtime.sim.loop``).

A :class:`Fault` names what goes wrong, from when (``start``, s), for how long (``duration``,
s), how badly (``magnitude``, in the kind's unit) and on which driven wheel. Faults act at
sample granularity: a fault covers the samples k with ``start <= k h < start + duration``,
and at least the first sample at or after ``start`` (so ``duration = 0`` means one sample).
The kinds, as the loop and the plant (``runtime.sim.plant``) apply them:

* ``encoder-glitch``: the wheel's quadrature counter gains ``magnitude`` counts (an integer,
  either sign) at the first sample at or after ``start``. ``duration = 0``: the miscount
  persists in the accumulated count, as a real encoder's lost or spurious edges do (the
  odometry pose keeps the heading error it causes); ``duration > 0``: the counts are read
  wrong only for that stretch (a corrupted read, not a miscount).
* ``dropped-sample``: the control task misses those samples: the controller's ``step`` is
  not called and the drive holds the previous torque (zero-order hold). The sensing keeps
  running (encoder counts, odometry and rates are computed on the sensor side).
* ``repeated-sample``: the controller is called, but receives the previous sample's
  measurement again (a stale packet); the sensing itself keeps running.
* ``traction-loss``: the wheel's contact transmits only ``1 - magnitude`` of the wheel's net
  torque (drive minus friction) to the ground; the rest spins the wheel relative to the
  ground on its own spin inertia (``magnitude`` in (0, 1], 1 = ice). Encoders and rates read
  the spinning wheel. When traction returns the spin rate stops at once (the contact
  dissipates it; its reaction on the body is neglected) and the slip angle stays in the
  encoder count. A proxy of slip in the no-slip plant, not a tyre-friction model: the
  constrained plant still carries the wheel's rolling inertia, so it is counted twice.
* ``torque-saturation``: the actuator delivers at most ``magnitude`` N m (either sign) on the
  wheel, whatever the controller commands; the controller is not told.

``wheel`` is ``right`` (the first driven wheel), ``left`` (the second) or ``both`` (not used
by the sample faults): the faults are written for two driven wheels.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FAULT_KINDS = (
    "encoder-glitch",
    "dropped-sample",
    "repeated-sample",
    "traction-loss",
    "torque-saturation",
)
SAMPLE_FAULTS = ("dropped-sample", "repeated-sample")  # no wheel, no magnitude
WHEELS = ("right", "left", "both")
UNITS = {"encoder-glitch": "counts", "traction-loss": "fraction lost", "torque-saturation": "N m"}


class FaultSpecError(ValueError):
    """A fault that cannot be injected; the message names the field."""


@dataclass(frozen=True)
class Fault:
    """One fault (see the module docstring for each kind's meaning of the fields)."""

    kind: str
    start: float  # s
    duration: float = 0.0  # s
    magnitude: float = 0.0  # counts, fraction of traction lost, or N m
    wheel: str = "right"

    def __post_init__(self) -> None:
        check_fault(self)

    @property
    def wheels(self) -> NDArray[np.float64]:
        """1 on the wheels the fault touches, (right, left)."""
        return np.array({"right": [1.0, 0.0], "left": [0.0, 1.0], "both": [1.0, 1.0]}[self.wheel])

    @property
    def persists(self) -> bool:
        """A persisting encoder miscount (active from ``start`` to the end of the run)."""
        return self.kind == "encoder-glitch" and self.duration == 0

    def samples(self, h: float, n: int) -> range:
        """The sample indices the fault covers in a run of ``n`` samples of ``h`` s (never
        sample 0, which starts the run on the reference)."""
        tol = 1e-9
        k0 = max(1, math.ceil(self.start / h - tol))
        if self.persists:
            return range(min(k0, n), n)
        k1 = max(k0 + 1, math.ceil((self.start + self.duration) / h - tol))
        return range(min(k0, n), min(k1, n))

    def label(self) -> str:
        """A short name for a table row: kind, size and span."""
        size = {
            "encoder-glitch": f" {self.magnitude:+g} counts {self.wheel}",
            "traction-loss": f" {self.magnitude:g} {self.wheel}",
            "torque-saturation": f" {self.magnitude:g} N m {self.wheel}",
        }.get(self.kind, "")
        span = (
            "persisting"
            if self.persists
            else f"{self.duration:g} s"
            if self.duration
            else "1 sample"
        )
        return f"{self.kind}{size}, {span}"

    def describe(self) -> str:
        """One line naming the fault and its parameters."""
        span = (
            "persisting"
            if self.persists
            else f"{self.duration:g} s"
            if self.duration > 0
            else "one sample"
        )
        what = {
            "encoder-glitch": f"{self.magnitude:+g} counts on the {self.wheel} encoder",
            "dropped-sample": "controller not called, torque held",
            "repeated-sample": "previous measurement delivered again",
            "traction-loss": f"{self.magnitude:g} of the {self.wheel} wheel's traction lost",
            "torque-saturation": f"actuator limited to {self.magnitude:g} N m on {self.wheel}"
            + (" wheels" if self.wheel == "both" else " wheel"),
        }[self.kind]
        return f"{self.kind} at {self.start:g} s, {span}: {what}"


def check_fault(f: Fault) -> None:
    """Raise :class:`FaultSpecError` (one line naming the field) if ``f`` is not valid."""
    if f.kind not in FAULT_KINDS:
        raise FaultSpecError(
            f"field 'kind' must be one of {', '.join(repr(k) for k in FAULT_KINDS)}, got {f.kind!r}"
        )
    for name in ("start", "duration", "magnitude"):
        value = getattr(f, name)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise FaultSpecError(f"field '{name}' must be a number, got {value!r}")
        if not math.isfinite(value):
            raise FaultSpecError(f"field '{name}' must be finite, got {value!r}")
    if f.start <= 0:
        raise FaultSpecError(f"field 'start' must be positive (s), got {f.start!r}")
    if f.duration < 0:
        raise FaultSpecError(f"field 'duration' must be non-negative (s), got {f.duration!r}")
    if f.wheel not in WHEELS:
        raise FaultSpecError(
            f"field 'wheel' must be one of {', '.join(repr(w) for w in WHEELS)}, got {f.wheel!r}"
        )
    if f.kind in SAMPLE_FAULTS:
        if f.magnitude != 0:
            raise FaultSpecError(f"field 'magnitude' is not used by {f.kind!r}; leave it out")
        if f.wheel != "right":
            raise FaultSpecError(f"field 'wheel' is not used by {f.kind!r}; leave it out")
    elif f.kind == "encoder-glitch":
        if f.magnitude == 0 or f.magnitude != int(f.magnitude):
            raise FaultSpecError(
                f"field 'magnitude' of 'encoder-glitch' must be a non-zero whole number of "
                f"counts, got {f.magnitude!r}"
            )
    else:
        if f.duration <= 0:
            raise FaultSpecError(f"field 'duration' of {f.kind!r} must be positive (s)")
        if f.kind == "traction-loss" and not 0 < f.magnitude <= 1:
            raise FaultSpecError(
                f"field 'magnitude' of 'traction-loss' must be in (0, 1] (fraction of traction "
                f"lost), got {f.magnitude!r}"
            )
        if f.kind == "torque-saturation" and f.magnitude <= 0:
            raise FaultSpecError(
                f"field 'magnitude' of 'torque-saturation' must be a positive torque (N m), got "
                f"{f.magnitude!r}"
            )


FIELDS = ("kind", "start", "duration", "magnitude", "wheel")


def fault_from_table(data: object) -> Fault:
    """A fault from one ``[[fault]]`` table of an experiment file."""
    if not isinstance(data, dict):
        raise FaultSpecError("must be a table")
    unknown = sorted(set(data) - set(FIELDS))
    if unknown:
        raise FaultSpecError(f"unknown field '{unknown[0]}' (expected one of {', '.join(FIELDS)})")
    for required in ("kind", "start"):
        if required not in data:
            raise FaultSpecError(f"field '{required}' is missing")
    for name in ("kind", "wheel"):
        if name in data and not isinstance(data[name], str):
            raise FaultSpecError(f"field '{name}' must be a string, got {data[name]!r}")
    return Fault(**data)


@dataclass(frozen=True)
class FaultSchedule:
    """The faults of one run, per sample k (n samples): what the simulator applies."""

    encoder_offset: NDArray[np.float64]  # (n, 2) counts added to the encoder readings
    dropped: NDArray[np.bool_]  # (n,) controller not called
    repeated: NDArray[np.bool_]  # (n,) controller fed the previous measurement
    traction_loss: NDArray[np.float64]  # (n, 2) fraction of torque not reaching the ground
    torque_limit: NDArray[np.float64]  # (n, 2) actuator limit, N m (inf: none)

    @property
    def any_loss(self) -> NDArray[np.bool_]:
        return np.asarray(self.traction_loss.any(axis=1))


def schedule(faults: Sequence[Fault], h: float, n: int) -> FaultSchedule:
    """Per-sample arrays of ``faults`` for a run of ``n`` samples of ``h`` s (overlapping
    faults add their counts, drop the most traction and take the lowest torque limit)."""
    offset = np.zeros((n, 2))
    dropped = np.zeros(n, dtype=bool)
    repeated = np.zeros(n, dtype=bool)
    loss = np.zeros((n, 2))
    limit = np.full((n, 2), np.inf)
    for f in faults:
        ks = list(f.samples(h, n))
        if not ks:
            continue
        w = f.wheels
        if f.kind == "encoder-glitch":
            offset[ks] += f.magnitude * w
        elif f.kind == "dropped-sample":
            dropped[ks] = True
        elif f.kind == "repeated-sample":
            repeated[ks] = True
        elif f.kind == "traction-loss":
            loss[ks] = np.maximum(loss[ks], f.magnitude * w)
        else:
            lim = np.where(w > 0, f.magnitude, np.inf)
            limit[ks] = np.minimum(limit[ks], lim)
    return FaultSchedule(offset, dropped, repeated, loss, limit)
