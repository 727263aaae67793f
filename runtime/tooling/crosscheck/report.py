"""The crosscheck's result: per robot, the deviation tables (a FAIL mark above tolerance) —
against the hand-written equations where they exist (:class:`Report`, with the derivation
checks) and against the robot's generated NumPy (:class:`GeneratedReport`) — and the
verdict (:class:`CrosscheckReport`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from modeling import audit
from runtime.tooling.crosscheck.deviation import (
    CONTROLLER_IMPLS,
    DOUBLE_TOL,
    FLOAT32_TOL,
    FUNCTION_IMPLS,
    GENERATED_FLOAT32_FLOOR,
    GENERATED_FLOAT32_TOL,
    IMPL_TITLES,
    IMPLS,
    Row,
    generated_tolerance,
    tolerance,
)


def table(
    title: str,
    rows: list[Row],
    width: int = 28,
    impls: Sequence[str] = IMPLS,
    bound: Callable[[str], float] = tolerance,
) -> tuple[str, int]:
    """The deviation table; each cell is the largest deviation and the quantity where it
    occurs; cells above tolerance (``bound(impl)``) are marked FAIL."""
    cw = 24
    lines = [title, f"{'':{width}}" + "".join(f"{IMPL_TITLES[i]:<{cw}}" for i in impls)]
    failures = 0
    for row in rows:
        cells = []
        for impl in impls:
            dev = row.cells[impl]
            ok = dev.value <= bound(impl)
            failures += not ok
            worst = dev.worst if dev.worst != row.name and len(dev.worst) <= 12 else ""
            if not ok and dev.worst != row.name:
                worst = dev.worst  # a failure names its quantity (or what is missing)
            text = f"{dev.value:8.1e} {worst:<8}{'' if ok else ' FAIL'}"
            cells.append(f"{text:<{cw}}")
        lines.append((f"{row.name:{width}}" + "".join(cells)).rstrip())
    return "\n".join(lines), failures


def _failing_rows(rows: Sequence[Row], bound: Callable[[str], float]) -> set[tuple[str, str]]:
    return {(r.name, i) for r in rows for i, d in r.cells.items() if not d.value <= bound(i)}


@dataclass
class Report:
    """What the comparison with the hand-written equations measured."""

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
        return bad | _failing_rows([*self.model_rows, *self.ctrl_rows], tolerance)

    def sections(self) -> list[str]:
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
            f"Tolerance: {DOUBLE_TOL:.0e} relative for double implementations, "
            f"{FLOAT32_TOL:.0e} for float32 (per step, identical float32 inputs and state)."
        )
        return out

    def render(self) -> str:
        out = self.sections()
        if self.perturb:
            out.append(f"Perturbed parameters: {self.perturb}")
        n = len(self.failing())
        verdict = "FAILED" if n else "PASSED"
        out.append(f"{verdict}: {n} deviation(s) above tolerance; {self.seconds:.1f} s")
        return "\n".join(out)


@dataclass
class GeneratedReport:
    """What the comparison with a robot's generated NumPy measured."""

    function_rows: list[Row]
    ctrl_rows: list[Row]
    cover: dict[str, int]
    n_samples: int
    n_sequences: int
    n_steps: int
    seconds: float

    def failing(self) -> set[tuple[str, str]]:
        return _failing_rows([*self.function_rows, *self.ctrl_rows], generated_tolerance)

    def sections(self) -> list[str]:
        out = []
        text, _ = table(
            f"Generated functions vs generated NumPy ({len(self.function_rows)} functions of "
            f"model, laws, plant; {self.n_samples} random states: q random, wheel rates "
            "random, the other velocities through the generated kinematics; parameters ±30 %)",
            self.function_rows, impls=FUNCTION_IMPLS, bound=generated_tolerance,
        )  # fmt: skip
        out.append(text)
        text, _ = table(
            f"\nC controllers vs generated Python classes ({self.n_sequences} sequences, "
            f"{self.n_steps} steps: closed loop + random near/far; quantities τ, gain, ‖s‖, "
            "Ĥ1, u_discarded, saturation status)",
            self.ctrl_rows, impls=CONTROLLER_IMPLS, bound=generated_tolerance,
        )  # fmt: skip
        out.append(text)
        out.append("Steps per branch: " + ", ".join(f"{k} {v}" for k, v in self.cover.items()))
        out.append(
            f"Tolerance: {DOUBLE_TOL:.0e} relative (to max(‖x_ref‖∞, 10⁻³·S)) for C double and "
            f"CasADi, {GENERATED_FLOAT32_TOL:.0e} for C float32 (relative to max(‖x_ref‖∞, "
            f"{GENERATED_FLOAT32_FLOOR:.0e}·S); identical float32 inputs and state)."
        )
        return out


@dataclass
class RobotReport:
    """One robot: its label, the hand-written comparison if it has one, the comparison with
    its generated NumPy."""

    name: str
    label: str
    handwritten: Report | None
    generated: GeneratedReport
    warnings: tuple[str, ...] = ()  # the physics audit's on the robot file

    def failing(self) -> set[tuple[str, str, str]]:
        """(section, row, implementation) above tolerance."""
        bad = {("generated", r, i) for r, i in self.generated.failing()}
        if self.handwritten is not None:
            bad |= {("hand-written", r, i) for r, i in self.handwritten.failing()}
        return bad

    def render(self) -> str:
        title = f"Robot {self.label}"
        out = [title, "=" * len(title), *audit.section(self.warnings, "Robot file audit")]
        if self.handwritten is not None:
            out += self.handwritten.sections()
            out.append("")
        else:
            out.append("No hand-written reference: the generated NumPy is the reference.\n")
        out += self.generated.sections()
        return "\n".join(out)


@dataclass
class CrosscheckReport:
    """Every robot checked, and the verdict."""

    robots: list[RobotReport]
    seconds: float
    perturb: dict[str, dict[str, float]]

    def robot(self, name: str) -> RobotReport:
        return next(r for r in self.robots if r.name == name)

    def failing(self) -> set[tuple[str, str, str, str]]:
        """(robot, section, row, implementation) above tolerance."""
        return {(r.name, *f) for r in self.robots for f in r.failing()}

    def render(self) -> str:
        out = [r.render() + "\n" for r in self.robots]
        if self.perturb:
            out.append(f"Perturbed parameters: {self.perturb}")
        n = len(self.failing())
        verdict = "FAILED" if n else "PASSED"
        names = ", ".join(r.name for r in self.robots)
        out.append(f"{verdict}: {n} deviation(s) above tolerance (robots: {names}); "
                   f"{self.seconds:.1f} s")
        return "\n".join(out)
