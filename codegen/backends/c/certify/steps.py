"""The controller steps' torque: each law's certificate with the errors its inputs carry
from the rest of the step.

A step (``wmr_<ctrl>_step``) computes, in float32: the tracking errors ``e = q_des - q``
and ``edot = qdot_des - qdot`` (one subtraction each), sin and cos of the angles
(``wmr_sincos_bounded``, 2 ulp), P from ``lyapunov_p`` (at ``_init``), H1hat from the
TDE kernel, k-hat from the weighted gain over the window's difference norms, then the
law; the torque is the law's rows of the driven wheels, saturated at tau_max (clamping
is 1-Lipschitz: the bound holds after it). Against the exact step (every one of those in
exact arithmetic on the same float32 inputs and state), the law's inputs therefore carry
the certified bounds of the functions that computed them: :func:`step_certificates`
certifies the law over its box with those input errors. The kernels a step inlines
(``wmr_kernels.h``) evaluate the same temporaries in the same order as the public
functions certified here (``codegen.backends.c.kernels`` splits one CSE at the
parameters); state carried across steps (the PI integral, the window) is taken as stored.
"""

from __future__ import annotations

from collections.abc import Collection, Iterator, Mapping
from dataclasses import dataclass

from codegen.backend import RobotTarget
from codegen.backends.c.certify.analysis import U
from codegen.backends.c.certify.bound import Certificate, certify
from codegen.backends.c.certify.boxes import DERIVED, ENVELOPE, Envelope, Interval
from codegen.backends.c.certify.program import Program
from codegen.backends.c.kernels import StepFeatures
from modeling.controllers import ControllerSpec


def chain(info: ControllerSpec) -> tuple[str, str, str]:
    """The (estimator, gain, law) name stems of a controller's step, "{f}" the formulation,
    from its declaration (:class:`~codegen.backends.c.kernels.StepFeatures`, what decides
    the kernels its step calls): (17)'s estimate if it has one, (25)'s window gain if it
    has a window, its law."""
    f = StepFeatures.of(info)
    return ("{f}_tde" if f.tde else "", "tdroc_weighted_gain" if f.window else "",
            f"{{f}}_{f.name}_law")


@dataclass(frozen=True)
class StepBound:
    controller: str
    formulation: str
    law: str
    torque_outputs: tuple[str, ...]
    bound: float  # N m, the largest over the driven wheels
    proved: bool
    reason: str
    tau_max: float


def _pick(names: set[str], stem: str, paper: bool) -> str:
    """The variant a step calls: ``_trig`` (paper: sin/cos once a step), ``_mhat``
    (M-hat evaluated once a step), else the plain function."""
    for suffix in (("_trig",) if paper else ("_mhat",)) + ("",):
        if stem + suffix in names:
            return stem + suffix
    return ""


@dataclass(frozen=True)
class Step:
    """One controller step and formulation: the functions whose certificates it combines."""

    controller: str
    formulation: str
    paper: bool
    law: str
    estimator: str  # "" without (17)'s estimate
    gain: str  # "" without (25)'s window gain

    @property
    def key(self) -> str:
        return f"{self.controller}/{self.formulation}"

    def reads(self, law: Program) -> frozenset[str]:
        """The functions whose certificate (bound or output enclosure) this step's bound
        uses, ``law`` the law's program: the law, estimator and gain, and the producers of
        the law's derived inputs (P's entries, M-hat)."""
        args = {access.split("[")[0] for access in law.input_names.values()}
        return frozenset(n for n in (self.law, self.estimator, self.gain) if n) | {
            fn for arg, (fn, _) in DERIVED.items() if arg.split("[")[0] in args}


def steps_of(target: RobotTarget, names: Collection[str]) -> Iterator[Step]:
    """Every controller step and formulation of ``target`` whose law is among ``names``
    (the robot's functions)."""
    forms = (("paper", True), ("minimal", False)) if target.layout.paper else (
        ("minimal", False),)
    for info in target.controllers:
        est, gain, law = chain(info)
        for form, paper in forms:
            law_name = _pick(set(names), law.format(f=form), paper)
            if law_name:
                yield Step(info.name, form, paper, law_name,
                           _pick(set(names), est.format(f=form), paper) if est else "", gain)


def step_certificates(target: RobotTarget,
                      certs: Mapping[str, tuple[Program, dict[object, Interval], Certificate]],
                      env: Envelope = ENVELOPE, seconds: float = 3.0,
                      only: Collection[str] | None = None) -> Iterator[StepBound]:
    """The torque bound of every controller step and formulation of ``target`` (``only``:
    of the steps with those :attr:`Step.key`)."""
    layout = target.layout

    def bound_of(name: str) -> float:
        return max(certs[name][2].bounds) if name in certs else float("inf")

    for step in steps_of(target, certs):
        if only is not None and step.key not in only:
            continue
        law_name, est_name, gain, paper = step.law, step.estimator, step.gain, step.paper
        prog, box, _ = certs[law_name]
        errs: dict[object, float] = {}
        notes: list[str] = []
        for sym, access in prog.input_names.items():
            arg = access.split("[")[0]
            if arg == "e":
                errs[sym] = U * max(abs(v) for v in box[sym])  # q_des - q, rounded once
            elif arg == "edot":
                errs[sym] = U * max(abs(v) for v in box[sym])
            elif arg in ("p12", "p22"):
                errs[sym] = bound_of("lyapunov_p")
            elif arg == "trig":
                errs[sym] = 4.0 * U
            elif arg == "H1hat" and est_name:
                errs[sym] = bound_of(est_name)
                lo, hi = box[sym]
                rng = certs[est_name][2].ranges
                if min(r[0] for r in rng) < lo or max(r[1] for r in rng) > hi:
                    notes.append(f"{est_name}'s output leaves the declared H1hat box")
            elif arg == "gain" and gain:
                errs[sym] = bound_of(gain)
            elif arg == "mhat":
                errs[sym] = bound_of("minimal_mhat")
        cert = certify(prog, box, errs, seconds=seconds)
        rows = (tuple(f"u[{i}]" for i in layout.actuated) if paper
                else tuple(f"u[{i}]" for i in range(layout.nu)))
        bounds = [cert.bounds[cert.outputs.index(r)] for r in rows if r in cert.outputs]
        yield StepBound(step.controller, step.formulation, law_name, rows,
                        max(bounds) if bounds else float("inf"),
                        cert.proved and not notes, "; ".join(dict.fromkeys(
                            [cert.reason] * (not cert.proved) + notes)),
                        env.torque)
