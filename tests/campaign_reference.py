"""A campaign's summary recomputed from its run records alone, to check ``summary.json`` and
``summary.md`` (:mod:`runtime.campaign.summary`) against
(``tests/runtime/test_campaign_summary.py``, ``tests/runtime/test_campaign.py``).

Written apart from the code under test on purpose: plain Python over the rows of
``results.parquet`` (percentiles by hand, linear between order statistics, numpy's default),
the predicted boundary read from the ε_min points the analysis gave, never through
``runtime.campaign.summary``. Only the outcome rules of ``runtime.campaign.runner`` are
taken as given: a run is a failure unless its status is ``ok``; ``ok`` and ``diverged``
runs are compared with the prediction; the ``ok`` runs make the percentiles.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq

STATUSES = ("ok", "diverged", "init_refused", "error")
METRICS = {"rms_error_m": "rms_error", "max_error_m": "max_error",
           "max_torque_Nm": "max_torque"}
Row = dict[str, Any]
# (controller, sensing.velocity) -> (y grid, ε_min at each point)
Boundaries = Mapping[tuple[str, str], tuple[Sequence[float], Sequence[float]]]


def records(out: Path) -> list[Row]:
    """The rows of ``out/results.parquet``, in run order."""
    rows = pq.read_table(out / "results.parquet").to_pylist()
    return sorted(rows, key=lambda r: r["index"])


def percentile(values: Sequence[float], p: float) -> float:
    """The p-th percentile, linear between the sorted values (rank p/100 (n − 1))."""
    v = sorted(values)
    if not v:
        return math.nan
    rank = p / 100 * (len(v) - 1)
    lo = math.floor(rank)
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (rank - lo) * (v[hi] - v[lo])


def eps_min_at(ys: Sequence[float], eps: Sequence[float], y: float) -> float:
    """ε_min at y: linear between the grid points, infinite next to an infinite one."""
    if len(ys) == 1 or y <= ys[0]:
        return eps[0]
    for i in range(1, len(ys)):
        if y <= ys[i]:
            if math.isinf(eps[i - 1]) or math.isinf(eps[i]):
                return math.inf
            w = (y - ys[i - 1]) / (ys[i] - ys[i - 1])
            return eps[i - 1] + w * (eps[i] - eps[i - 1])
    return eps[-1]


def verdicts(rows: Sequence[Row], boundaries: Boundaries, map_y: str,
             base: Mapping[str, Any]) -> list[bool]:
    """Per run: stable predicted (ε > ε_min(y) for its controller and sensing)? A parameter
    not drawn has its base value ``base[name]``."""
    def value(r: Row, name: str) -> Any:
        return r.get(f"p.{name}", base.get(name))

    out = []
    for r in rows:
        ys, eps = boundaries[(r["controller"], value(r, "sensing.velocity"))]
        out.append(value(r, "controller.eps") > eps_min_at(ys, eps, value(r, map_y)))
    return out


def _agreement(rows: Sequence[Row], predicted: Sequence[bool]) -> dict[str, int]:
    pairs = [(r["stable"], p) for r, p in zip(rows, predicted, strict=True)
             if r["status"] in ("ok", "diverged")]
    return {
        "runs": len(pairs),
        "agree": sum(1 for sim, p in pairs if sim == p),
        "predicted_stable_simulated_unstable": sum(1 for sim, p in pairs if p and not sim),
        "predicted_unstable_simulated_stable": sum(1 for sim, p in pairs if sim and not p),
    }


def expected_summary(rows: Sequence[Row], controllers: Sequence[str],
                     predicted: Sequence[bool]) -> dict[str, Any]:
    """What summary.json must say about ``rows`` (its numbers, NaN where undefined)."""
    per: dict[str, Any] = {}
    for ctrl in controllers:
        mine = [(r, p) for r, p in zip(rows, predicted, strict=True) if r["controller"] == ctrl]
        runs = [r for r, _ in mine]
        ok = [r for r in runs if r["status"] == "ok"]
        s: dict[str, Any] = {"runs": len(runs)}
        s.update({status: sum(1 for r in runs if r["status"] == status) for status in STATUSES})
        s["failure_rate"] = (len(runs) - len(ok)) / len(runs)
        s["unstable_rate"] = sum(1 for r in runs if not r["stable"]) / len(runs)
        for key, column in METRICS.items():
            values = [r[column] for r in ok if math.isfinite(r[column])]
            s[key] = {f"p{p}": percentile(values, p) for p in (50, 90, 99)}
            s[key]["max"] = max(values, default=math.nan)
        ran = [r for r in runs if r["status"] in ("ok", "diverged")
               and math.isfinite(r["max_error"])]
        worst = max(ran, key=lambda r: r["max_error"], default=None)
        s["worst"] = None if worst is None else {
            "index": worst["index"], "status": worst["status"],
            "max_error_m": worst["max_error"],
            "parameters": {k[2:]: v for k, v in worst.items() if k.startswith("p.")},
        }
        s["agreement"] = _agreement(runs, [p for _, p in mine])
        s["errors"] = sorted({r["error"] for r in runs if r["status"] == "error"})[:5]
        per[ctrl] = s
    return {"runs": len(rows), "controllers": per, "agreement": _agreement(rows, predicted)}


# ----------------------------------------------------------------------------- comparing


def _same(got: Any, want: Any, where: str) -> None:
    """``got`` (from JSON: NaN as None) equals ``want``: floats to 1e-12, the rest exactly."""
    if isinstance(want, dict):
        assert isinstance(got, dict), where
        for k, v in want.items():
            _same(got.get(k), v, f"{where}.{k}")
    elif isinstance(want, float) and math.isnan(want):
        assert got is None, (where, got)
    elif isinstance(want, float):
        assert isinstance(got, int | float) and math.isclose(got, want, rel_tol=1e-12), (
            where, got, want)
    else:
        assert got == want, (where, got, want)


def check_json(summary: Mapping[str, Any], expected: Mapping[str, Any]) -> None:
    """summary.json against :func:`expected_summary` (every number it holds there)."""
    _same(summary["runs"], expected["runs"], "runs")
    for ctrl, want in expected["controllers"].items():
        got = summary["controllers"][ctrl]
        agreement = want["agreement"]
        fraction = agreement["agree"] / agreement["runs"] if agreement["runs"] else math.nan
        _same(got, {**want, "agreement": {**agreement, "fraction": fraction}}, ctrl)
    total = expected["agreement"]
    _same(summary["agreement"], {"runs": total["runs"], "agree": total["agree"],
                                 "fraction": total["agree"] / total["runs"]}, "agreement")


def _close(cell: str, want: float, decimals: int, where: str) -> None:
    """A Markdown cell printed with ``decimals`` decimals holds ``want``."""
    if not math.isfinite(want):
        assert cell == "–", (where, cell)
        return
    assert abs(float(cell) - want) <= 0.5 * 10.0**-decimals + 1e-9, (where, cell, want)


def _table_rows(text: str, header_start: str) -> dict[str, list[str]]:
    """The cells of the Markdown table whose header line starts with ``header_start``, by
    their first cell."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(header_start)) + 2
    rows: dict[str, list[str]] = {}
    for line in lines[start:]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        rows[cells[0]] = cells
    return rows


def check_markdown(text: str, expected: Mapping[str, Any]) -> None:
    """summary.md's outcome table, agreement sentence and table, and error list against
    :func:`expected_summary`."""
    assert text.startswith(f"# Campaign summary: {expected['runs']} runs\n")
    outcome = _table_rows(text, "| controller | runs | ok |")
    compared = _table_rows(text, "| controller | runs compared |")
    assert set(outcome) == set(compared) == {c.upper() for c in expected["controllers"]}
    for ctrl, s in expected["controllers"].items():
        cells = outcome[ctrl.upper()]
        where = f"summary.md {ctrl}"
        assert [int(c) for c in cells[1:6]] == [s["runs"], *(s[k] for k in STATUSES)], where
        for cell, rate in ((cells[6], s["failure_rate"]), (cells[7], s["unstable_rate"])):
            assert cell.endswith(" %"), (where, cell)
            _close(cell.removesuffix(" %"), 100 * rate, 1, where)
        rms = s["rms_error_m"]
        parts = cells[8].split(" / ")
        for part, key in zip(parts, ("p50", "p90", "p99", "max"), strict=True):
            _close(part, 1000 * rms[key], 2, f"{where} RMS error {key}")
        worst = s["worst"]
        m = re.fullmatch(r"(\S+) \(#(\d+)\)", cells[9])
        if worst is None:
            assert cells[9] == "–", (where, cells[9])
        else:
            assert m is not None, (where, cells[9])
            _close(m.group(1), 1000 * worst["max_error_m"], 2, f"{where} worst")
            assert int(m.group(2)) == worst["index"], (where, cells[9])
        p99 = s["max_torque_Nm"]["p99"]
        assert math.isclose(float(cells[10]), p99, rel_tol=5e-3), (where, cells[10], p99)
        a = s["agreement"]
        row = compared[ctrl.upper()]
        assert int(row[1]) == a["runs"], (where, row)
        _close(row[2].removesuffix(" %"), 100 * a["agree"] / a["runs"] if a["runs"] else math.nan,
               1, where)
        assert [int(row[3]), int(row[4])] == [a["predicted_stable_simulated_unstable"],
                                              a["predicted_unstable_simulated_stable"]], row
        for message in s["errors"]:
            assert f"- {ctrl.upper()}: {message}" in text, (where, message)
    total = expected["agreement"]
    m = re.search(r"Agreement: (\d+) of (\d+) runs \(([\d.]+) %\)", text)
    assert m is not None
    assert (int(m.group(1)), int(m.group(2))) == (total["agree"], total["runs"])
    _close(m.group(3), 100 * total["agree"] / total["runs"], 1, "summary.md agreement")
