"""One verdict per printed equation: every transcription judged once (cached).

:func:`judgements` keeps the data behind each verdict (sign assignment, residual) for the
report and the tests; :func:`verdicts` is the summary per equation. The first call takes
about three seconds (the engine's derivation dominates).
"""
from __future__ import annotations

import functools
from collections.abc import Iterable

from modeling.robots.drishti.paper.signs import Judgement, Verdict, VerdictKind, judge
from modeling.robots.drishti.paper.transcriptions import transcriptions


@functools.cache
def _judgements() -> tuple[Judgement, ...]:
    return tuple(judge(t) for t in transcriptions())


def judgements() -> list[Judgement]:
    """The verdicts with the data behind them (cached: the derivation runs once)."""
    return list(_judgements())


def verdicts() -> list[Verdict]:
    """One verdict per printed equation (or printed matrix of an equation)."""
    return [j.as_verdict() for j in _judgements()]


def verdict_table(items: Iterable[Verdict] | None = None) -> dict[str, VerdictKind]:
    """equation → verdict."""
    return {v.equation: v.verdict for v in (verdicts() if items is None else items)}
