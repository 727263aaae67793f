"""The controller steps' torque: each law's certificate with the errors its inputs carry
from the rest of the step.

A step (``wmr_<ctrl>_step``) computes, in float32: the tracking errors ``e = q_des - q``
and ``edot = qdot_des - qdot`` (one subtraction each), sin and cos of the angles
(``wmr_sincos_checked``, 2 ulp), P from ``lyapunov_p`` (at ``_init``), H1hat from the
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
from codegen.backends.c.certify.boxes import ENVELOPE, Envelope, Interval, producers
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
    norm: str = ""  # the ||M-hat^-1|| function (25)'s gain reads
    adaptive: bool = False  # the law's gain is adapted and carried in the state (ASMC)

    @property
    def key(self) -> str:
        return f"{self.controller}/{self.formulation}"

    def reads(self, law: Program) -> frozenset[str]:
        """The functions whose certificate (bound or output enclosure) this step's bound
        uses, ``law`` the law's program: the law, estimator and gain, and the producers of
        the law's derived inputs (P's entries, M-hat)."""
        return frozenset(n for n in (self.law, self.estimator, self.gain, self.norm)
                         if n) | producers(law)


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
                           _pick(set(names), est.format(f=form), paper) if est else "", gain,
                           _pick(set(names), f"{form}_minv_norm", paper) if gain else "",
                           info.adaptive)


def _gain_conditions(certs: Mapping[str, tuple[Program, Mapping[object, Interval],
                                                Certificate]],
                     step: Step, declared: Interval, law_box: Mapping[object, Interval]
                     ) -> list[str]:
    """The conditions ("if ...") a TDROC step's bound holds under: (25)'s k-hat and the
    gain function's inputs within the boxes the law's and the gain's certificates hold
    over, wherever the certified enclosures do not prove it (the step checks none of
    these: k-hat is capped at GAIN_MAX = 1e6 only): k-hat's enclosure against the law's
    gain box; ||M-hat^-1||'s (the norm function's enclosure) and the window's difference
    norms' (at most 2 sqrt(sum of max|H1hat_i|^2) over the law's H1hat box, i.e. the
    estimator's enclosure) against the gain function's boxes. The step checks none of them;
    ``<prefix>_tdroc_within_certificate`` (:mod:`codegen.certify.runtime_check`, the same
    boxes) checks them after a step, and the reports name it in these rows
    (:func:`~codegen.certify.runtime_check.checked_by`)."""
    notes: list[str] = []
    gprog, gbox, gcert = certs[step.gain]
    top = max(r[1] for r in gcert.ranges)
    if top > declared[1]:
        notes.append(f"if k-hat stays in the law's gain box [{declared[0]:g}, {declared[1]:g}]"
                     f" ({step.gain}'s enclosure reaches {top:.3g})")
    inputs = {a.split("[")[0]: gbox[s] for s, a in gprog.input_names.items()}
    if step.norm in certs and "minv_norm" in inputs:
        top = max(r[1] for r in certs[step.norm][2].ranges)
        if top > inputs["minv_norm"][1]:
            notes.append(f"if the norm of M-hat^-1 stays in {step.gain}'s box [0, "
                         f"{inputs['minv_norm'][1]:g}] ({step.norm}'s enclosure reaches "
                         f"{top:.3g})")
    law = certs[step.law][0]
    h = [max(abs(b[0]), abs(b[1])) for s, b in law_box.items()
         if law.input_names.get(s, "").startswith("H1hat")]
    if h and "dn_new" in inputs:
        top = 2.0 * sum(v * v for v in h) ** 0.5
        if top > inputs["dn_new"][1]:
            notes.append(f"if the window's difference norms stay in {step.gain}'s box "
                         f"[0, {inputs['dn_new'][1]:g}] (over the estimate's enclosure they "
                         f"reach {top:.3g})")
    return notes


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
        prog, declared, _ = certs[law_name]
        box = dict(declared)
        errs: dict[object, float] = {}
        notes: list[str] = []
        gain_box: Interval | None = None
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
                # (17)'s estimate as the step computes it: over the estimator's certified
                # output enclosure (every state and history in its box), not the law's
                # declared H1hat box, which that enclosure exceeds (docs/FLOAT32.md)
                errs[sym] = bound_of(est_name)
                est = certs[est_name][2]
                rng = ([est.ranges[est.outputs.index(access)]] if access in est.outputs
                       else est.ranges)
                box[sym] = (min(box[sym][0], *(r[0] for r in rng)),
                            max(box[sym][1], *(r[1] for r in rng)))
            elif arg == "gain" and gain:
                errs[sym] = bound_of(gain)
                gain_box = box[sym]
            elif arg == "gain" and step.adaptive:
                # the adapted gain is the state's, which the step does not keep in the law's
                # box: <prefix>_asmc_within_certificate (codegen.certify.runtime_check)
                # checks it after a step
                notes.append(f"if the adapted gain the state carries stays in the law's "
                             f"gain box [{box[sym][0]:g}, {box[sym][1]:g}] (the step caps "
                             "it at GAIN_MAX only)")
            elif arg == "mhat":
                errs[sym] = bound_of("minimal_mhat")
        if gain_box is not None:  # after the loop: box's H1hat entries are the estimate's
            notes += _gain_conditions(certs, step, gain_box, box)
        cert = certify(prog, box, errs, seconds=seconds)
        rows = (tuple(f"u[{i}]" for i in layout.actuated) if paper
                else tuple(f"u[{i}]" for i in range(layout.nu)))
        bounds = [cert.bounds[cert.outputs.index(r)] for r in rows if r in cert.outputs]
        yield StepBound(step.controller, step.formulation, law_name, rows,
                        max(bounds) if bounds else float("inf"),
                        cert.proved and not notes, "; ".join(dict.fromkeys(
                            [cert.reason] * (not cert.proved) + notes)),
                        env.torque)
