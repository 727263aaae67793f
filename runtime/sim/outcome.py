"""Whether a closed-loop run is "ok", said the same way by every command.

A run is ``ok`` only if its configuration was accepted (by the checks, then by ``_init``),
no step failed, the plant stayed finite, and the root's frame origin stayed on its path:
its final and RMS distance from the reference are both within :data:`OFF_PATH_FRACTION` of
the path's scale (the circle's radius, the spacing of the lawn mower's legs). A run that
ends a path's size away from it has not tracked it, whatever its controller reported.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from runtime.sim.loop import Run

# A run whose final or RMS position error exceeds this fraction of its path's scale is off
# the path: 10 % of the circle's radius (15 cm for Drishti's 1.5 m), far above the
# millimetres a working controller tracks to and far below a run that has lost the path.
OFF_PATH_FRACTION = 0.10


@dataclass(frozen=True)
class Outcome:
    """``status``: ``ok``, ``off path``, ``failed``, ``init refused`` (by the C ``_init``) or
    ``refused`` (by the configuration checks, before the run); ``detail``: the sentence
    saying why (empty for ``ok``)."""

    status: str
    detail: str

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def describe(self) -> str:
        return self.status if self.ok else f"{self.status}: {self.detail}"


def outcome(run: Run, scale: float) -> Outcome:
    """The outcome of ``run`` on a path of scale ``scale`` (m)."""
    if run.init_status != 0:
        return Outcome("init refused", run.stop_reason or f"status {run.init_status}")
    if run.refused is not None:
        return Outcome("refused", run.refused)
    if run.failed_at is not None:
        return Outcome("failed", f"at {run.failed_at:g} s, {run.stop_reason}")
    e = run.position_error
    final, rms = float(e[-1]), float(np.sqrt(np.mean(e**2)))
    limit = OFF_PATH_FRACTION * scale
    if not (final <= limit and rms <= limit):
        return Outcome("off path", f"final error {final:.3g} m, RMS {rms:.3g} m; more than "
                       f"{100 * OFF_PATH_FRACTION:g} % of the path's {scale:.3g} m")
    return Outcome("ok", "")
