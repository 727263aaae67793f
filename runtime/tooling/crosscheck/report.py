"""The crosscheck's result: the deviation tables (a FAIL mark above tolerance), the
derivation checks and the verdict.
"""

from __future__ import annotations

from dataclasses import dataclass

from runtime.tooling.crosscheck.deviation import (
    DOUBLE_TOL,
    FLOAT32_TOL,
    IMPL_TITLES,
    IMPLS,
    Row,
    tolerance,
)


def table(title: str, rows: list[Row], width: int = 28) -> tuple[str, int]:
    """The deviation table; each cell is the largest deviation and the quantity where it
    occurs; cells above tolerance are marked FAIL."""
    cw = 24
    lines = [title, f"{'':{width}}" + "".join(f"{IMPL_TITLES[i]:<{cw}}" for i in IMPLS)]
    failures = 0
    for row in rows:
        cells = []
        for impl in IMPLS:
            dev = row.cells[impl]
            ok = dev.value <= tolerance(impl)
            failures += not ok
            worst = dev.worst if dev.worst != row.name and len(dev.worst) <= 10 else ""
            text = f"{dev.value:8.1e} {worst:<8}{'' if ok else ' FAIL'}"
            cells.append(f"{text:<{cw}}")
        lines.append((f"{row.name:{width}}" + "".join(cells)).rstrip())
    return "\n".join(lines), failures


@dataclass
class Report:
    """Everything the crosscheck measured."""

    checks: list[tuple[str, float, bool]]
    model_rows: list[Row]
    ctrl_rows: list[Row]
    cover: dict[str, int]
    n_samples: int
    n_sequences: int
    n_steps: int
    seconds: float
    perturb: dict[str, dict[str, float]]

    def failing(self) -> set[tuple[str, str]]:
        """(row, implementation) pairs above tolerance; ("self", name) for derivation checks."""
        bad = {("self", n) for n, v, gated in self.checks if gated and not v <= DOUBLE_TOL}
        for row in (*self.model_rows, *self.ctrl_rows):
            bad |= {(row.name, i) for i, d in row.cells.items() if not d.value <= tolerance(i)}
        return bad

    def render(self) -> str:
        out = ["Hand-written equations: derivation checks (max relative deviation)"]
        for name, value, gated in self.checks:
            bad = gated and not value <= DOUBLE_TOL
            out.append(f"  {name:64} {value:9.2e}{' FAIL' if bad else ''}")
        text, _ = table(
            f"\nModel functions vs hand-written ({self.n_samples} random samples, "
            "parameters ±30 %)",
            self.model_rows,
        )
        out.append(text)
        text, _ = table(
            f"\nController steps vs hand-written ({self.n_sequences} sequences, {self.n_steps} "
            "steps: closed loop + random near/far; quantities τ, gain, ‖s‖, Ĥ1, ‖u₁₋₃‖; "
            "CasADi: TDE, ‖M̂⁻¹‖, TDROC gain, law and Lyapunov kernels)",
            self.ctrl_rows,
        )
        out.append(text)
        out.append("Steps per branch: " + ", ".join(f"{k} {v}" for k, v in self.cover.items()))
        out.append(
            f"\nTolerance: {DOUBLE_TOL:.0e} relative for double implementations, "
            f"{FLOAT32_TOL:.0e} for float32 (per step, identical float32 inputs and state)."
        )
        if self.perturb:
            out.append(f"Perturbed parameters: {self.perturb}")
        n = len(self.failing())
        verdict = "FAILED" if n else "PASSED"
        out.append(f"{verdict}: {n} deviation(s) above tolerance; {self.seconds:.1f} s")
        return "\n".join(out)
