"""A run's outcome (runtime/sim/outcome.py) on runs that cross ONE limit and not the other.

"ok" needs both the final and the RMS distance from the path within 10 % of its scale: a
run that ends off the path but tracked it on average, and one that wandered off and came
back at the end, are both "off path". A test that shifts a whole run cannot tell ``and``
from ``or`` in that rule; these runs can.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from runtime.sim.loop import Run
from runtime.sim.outcome import OFF_PATH_FRACTION, outcome

SCALE = 1.5  # m: Drishti's circle radius
LIMIT = OFF_PATH_FRACTION * SCALE


def run_with_error(error: np.ndarray, **fields: object) -> Run:
    """A run whose root's distance from its reference is ``error`` (m) per sample; every
    other field empty (outcome reads none of them)."""
    n = len(error)
    q = np.zeros((n, 3))
    q[:, 0] = error  # the reference stays at the origin: the distance is x
    values: dict[str, object] = {}
    for f in dataclasses.fields(Run):
        if f.default is not dataclasses.MISSING:
            continue
        values[f.name] = (0 if f.type in ("int",) else
                          None if "None" in str(f.type) else
                          "tdc" if f.type == "str" else np.zeros((n, 3)))
    values.update(t=np.arange(n) * 0.05, q=q, q_des=np.zeros((n, 3)))
    values.update(fields)
    return Run(**values)  # type: ignore[arg-type]


def _rms(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(e**2)))


def test_on_path_is_ok() -> None:
    e = np.full(100, 0.5 * LIMIT)
    assert outcome(run_with_error(e), SCALE).status == "ok"


def test_ends_off_path_though_its_rms_is_within() -> None:
    """Tracked within the limit all along but the last sample: final > limit, RMS < limit."""
    e = np.full(400, 0.1 * LIMIT)
    e[-1] = 3 * LIMIT
    assert _rms(e) < LIMIT < e[-1]
    result = outcome(run_with_error(e), SCALE)
    assert result.status == "off path", result
    assert f"final error {e[-1]:.3g} m" in result.detail


def test_wandered_off_and_came_back() -> None:
    """Far off the path for most of the run, back on it at the end: RMS > limit, final <
    limit."""
    e = np.full(100, 2 * LIMIT)
    e[-1] = 0.1 * LIMIT
    assert e[-1] < LIMIT < _rms(e)
    result = outcome(run_with_error(e), SCALE)
    assert result.status == "off path", result
    assert f"RMS {_rms(e):.3g} m" in result.detail


@pytest.mark.parametrize("factor", [0.999, 1.0])
def test_the_limit_itself_is_on_path(factor: float) -> None:
    e = np.full(10, factor * LIMIT)
    assert outcome(run_with_error(e), SCALE).ok


def test_just_past_the_limit_is_off_path() -> None:
    e = np.full(10, 1.001 * LIMIT)
    assert outcome(run_with_error(e), SCALE).status == "off path"


def test_refused_and_failed_come_before_the_path() -> None:
    e = np.zeros(10)
    refused = outcome(run_with_error(e, init_status=-3, stop_reason="bad gain"), SCALE)
    assert (refused.status, refused.detail) == ("init refused", "bad gain")
    failed = outcome(run_with_error(e, failed_at=1.25, stop_reason="WMR_ERR_X"), SCALE)
    assert failed.status == "failed" and "at 1.25 s, WMR_ERR_X" in failed.detail
