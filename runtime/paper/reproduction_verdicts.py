"""Verdicts on the runs of the paper's robot's reproduction (:mod:`runtime.reproduction.driver`),
per sensing model:

* :func:`claims`: the paper's three claims (Section 5, Figures 4–8 and 11–14), each with
  whether it reproduces and the evidence; :func:`best`: the controller with the lowest RMS
  error on a path in a formulation;
* :func:`stability`: the ultimate bounds (21) (TDC), (27) and (30) (TDROC) from the gains
  and the measured time-delay estimation error k̄ of (23), beside the measured errors;
* :func:`stable_on_all_paths`: the swept ε of (25) at which TDROC is stable (RMS error
  within ``UNSTABLE_FACTOR`` × TDC's, no failure) on every path.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from runtime.paper.reproduction_tables import fmt_mm
from runtime.reproduction.driver import Reproduction


@dataclass(frozen=True)
class Claim:
    text: str
    holds: bool
    evidence: str


def best(rep: Reproduction, sensing: str, path: str, formulation: str) -> str:
    rows = [m for m in rep.rows(sensing) if m.path == path and m.formulation == formulation]
    return min(rows, key=lambda m: m.rms_error).controller


def claims(rep: Reproduction, sensing: str) -> list[Claim]:
    """The paper's three claims (Section 5, Figures 4–8 and 11–14), evaluated on the runs of
    one sensing model: (1) TDROC tracks best of the four (paper formulation, both paths);
    (2) ASMC's k̂ never decreases (both formulations and paths); (3) TDROC's median k̂ is
    the lowest of TDROC, ROC, ASMC (paper formulation, both paths)."""
    out = []
    winners = {p: best(rep, sensing, p, "paper") for p in rep.refs}
    rms_of = {
        (m.path, m.controller): m.rms_error for m in rep.rows(sensing) if m.formulation == "paper"
    }
    out.append(
        Claim(
            "TDROC has the lowest tracking error of the four controllers on both paths",
            all(w == "tdroc" for w in winners.values()),
            "; ".join(
                f"{p}: lowest RMS by {rep.labels[w]} (TDROC {fmt_mm(rms_of[(p, 'tdroc')])} mm, "
                f"TDC {fmt_mm(rms_of[(p, 'tdc')])} mm, ROC {fmt_mm(rms_of[(p, 'roc')])} mm, "
                f"ASMC {fmt_mm(rms_of[(p, 'asmc')])} mm; TDROC/TDC "
                f"{rms_of[(p, 'tdroc')] / rms_of[(p, 'tdc')]:.3f})"
                for p, w in winners.items()
            ),
        )
    )
    diffs = [
        float(np.diff(rep.runs[(sensing, "asmc", f, p)].gain).min())
        for f in rep.code.formulations
        for p in rep.refs
    ]
    out.append(
        Claim(
            "ASMC's switching gain grows monotonically",
            min(diffs) >= 0.0,
            f"smallest step-to-step change of k̂ (both formulations and paths): {min(diffs):.3g}",
        )
    )
    lowest = {}
    for p in rep.refs:
        med = {
            c: float(np.median(rep.runs[(sensing, c, "paper", p)].gain))
            for c in ("tdroc", "roc", "asmc")
        }
        lowest[p] = (min(med, key=lambda c: med[c]), med)
    out.append(
        Claim(
            "TDROC's switching gain is the lowest of TDROC, ROC and ASMC",
            all(c == "tdroc" for c, _ in lowest.values()),
            "; ".join(
                f"{p}: median k̂ " + ", ".join(f"{rep.labels[c]} {v:.3g}" for c, v in med.items())
                for p, (_, med) in lowest.items()
            ),
        )
    )
    return out


@dataclass(frozen=True)
class StabilityRow:
    sensing: str
    controller: str
    path: str
    tde_bound: float  # k̄ of (23), measured: max ‖M̂⁻¹‖ ‖Ĥ1(t + h) − Ĥ1(t)‖
    varpi: float  # ϖ1 of (21) (TDC) or ϖ3 of (30) (TDROC)
    ultimate_bound: float  # √(λmax(P)/λmin(P)) ϖ
    measured: float  # max ‖(e, ė)‖ after the start-up (t > 5 s)
    varpi2: float | None = None  # ϖ2 of (27) (TDROC, ‖s‖ ≥ ε): 2 max(k̄ − k̂, 0)‖BᵀP‖/λmin(Q)


def stability(
    rep: Reproduction, sensing: str, robot: dict[str, float] | None = None
) -> list[StabilityRow]:
    """The ultimate bounds (21) (TDC) and (30) (TDROC) for the experiment's gains and the
    measured time-delay estimation error, beside the measured errors (paper formulation,
    one sensing model).

    (21): ϖ1 = 2‖PB‖ k̄ / λmin(Q); (27) (case ‖s‖ ≥ ε of Theorem 2):
    ϖ2 = 2 (k̄ − k̂)‖BᵀP‖ / λmin(Q), zero when k̂ ≥ k̄; (30): ϖ3 = √(ε k̄² / (2 k̂ λmin(Q)))
    with k̂ the median switching gain; each ultimate bound is √(λmax(P)/λmin(P)) ϖ.
    """
    laws = rep.code.laws
    robot = dict(robot or rep.robot or rep.code.params)
    c = rep.experiment.controller
    p11, p12, p22 = laws.lyapunov_p([c.k1, c.k2, c.q_pos, c.q_vel])
    eig = np.linalg.eigvalsh(np.array([[p11, p12], [p12, p22]]))
    cond = float(np.sqrt(eig.max() / eig.min()))
    pb = float(np.hypot(p12, p22))
    lam_q = min(c.q_pos, c.q_vel)
    minv = float(laws.paper_minv_norm(robot)[0])
    rows = []
    for path in rep.refs:
        for ctrl in ("tdc", "tdroc"):
            r = rep.runs[(sensing, ctrl, "paper", path)]
            late = r.t[1:] > min(2.0, 0.25 * r.t[-1])
            kbar = float(minv * np.linalg.norm(np.diff(r.h1hat, axis=0), axis=1)[late].max())
            varpi2 = None
            if ctrl == "tdc":
                varpi = 2 * pb * kbar / lam_q
            else:
                khat = max(float(np.median(r.gain)), 1e-12)
                varpi = float(np.sqrt(c.eps * kbar**2 / (2 * khat * lam_q)))
                varpi2 = 2 * max(kbar - khat, 0.0) * pb / lam_q
            measured = float(r.error_norm[r.t >= min(5.0, 0.5 * r.t[-1])].max())
            rows.append(
                StabilityRow(sensing, ctrl, path, kbar, varpi, cond * varpi, measured, varpi2)
            )
    return rows


def stable_on_all_paths(rep: Reproduction, sensing: str, estimator: str) -> list[float]:
    """The swept ε at which TDROC is stable on every path (sensing, estimator)."""
    rows = [s for s in rep.sweep if s.sensing == sensing and s.estimator == estimator]
    return sorted({s.eps for s in rows} - {s.eps for s in rows if not s.stable})
