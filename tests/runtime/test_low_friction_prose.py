"""docs/MUJOCO.md's low-friction prose says what the runs measured (issue 45): how many
runs end on the path at the lowest floor (not that the others lose it "for good", which no
run measures), and how many still slip under the traction limit, with when. The
comparison's runs are stood in for by cells with known outcomes. Instant.
"""

from __future__ import annotations

from types import SimpleNamespace

from runtime.plant_comparison import Cell, _summary

CASES = (("μ = 1", 1.0, 0.0), ("μ = 0.1", 0.1, 0.0), ("μ = 0.1, traction limit", 0.1, 0.1))


def _cell(status: str, onset: float | None) -> Cell:
    return Cell(0.01, 0.02, status, 0, 0.0, onset, 0.1)


def _comparison(outcomes: list[tuple[str, str, float | None]]) -> SimpleNamespace:
    """One row per (outcome at μ = 0.1, outcome under the limit, slip onset under it)."""
    rows = [SimpleNamespace(formulation="paper", model=_cell("ok", None), engine=(
        _cell("ok", None), _cell(low, 1.0 if low != "ok" else None), _cell(lim, onset)))
        for low, lim, onset in outcomes]
    return SimpleNamespace(cases=CASES, rows=rows)


def test_the_prose_counts_what_the_runs_measured() -> None:
    comp = _comparison([("ok", "ok", None), ("diverged", "ok", 26.2),
                        ("off path", "ok", 8.9), ("diverged", "off path", None)])
    text = " ".join(_summary(comp))  # type: ignore[arg-type]
    assert "for good" not in text
    assert "1 of 4 runs end on the path" in text
    assert "2 of 4 runs still slip under it" in text and "first slip 8.9 … 26.2 s" in text


def test_no_slip_under_the_limit_is_said_as_measured() -> None:
    text = " ".join(_summary(_comparison([("ok", "ok", None)])))  # type: ignore[arg-type]
    assert "no run slips under it" in text and "still slip" not in text
