"""The stability boundary the sampled-data analysis predicts on a campaign's map.

:func:`runtime.stability.analysis.analyse` gives, for a controller at a setting, the largest
stable boundary-layer gain g_max and the gain the setting gives, g = N/ε with N = 0 (TDC),
k̂ measured in closed loop (TDROC, ASMC) or ρ (ROC). So the loop is predicted stable for
ε > ε_min = N / g_max (no ε if it is unstable without switching: ε_min = ∞). ε_min is
computed at ``map.grid`` points of the map's y parameter over its drawn range, for each
controller and each sensing model the campaign draws, every other parameter at its base
value (nominal robot, no payload, no friction: the analysis' conditions), and interpolated
in between. Every robot whose first coordinates are its pose (Drishti, [lumped] and
[physical] robots, bodies and wheels: trailers, casters) has the analysis, for the laws of
(18): a controller without a switching term (the PI) or one the analysis does not model
gets no boundary.

Grip: beside the boundary, each controller's saturation and grip verdict at the
campaign's base setting (:func:`grip_verdicts`: ``wmr stability``'s, the same function),
which the summary states (``slips``: the time, wheel and margin, and the ``traction_mu``
to set). The map's runs are drawn over many settings; the verdict is the base one's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from runtime.campaign.runner import Target
from runtime.campaign.spec import Campaign, with_values
from runtime.stability.saturation import grip_data, saturation_verdict

BIG = 1e12


@dataclass(frozen=True)
class Boundary:
    """ε_min over the y grid for one controller and sensing model."""

    controller: str
    velocity: str
    y: tuple[float, ...]
    eps_min: tuple[float, ...]  # inf: unstable without switching; 0: stable for every ε

    def eps_at(self, y: float) -> float:
        e = np.minimum(np.array(self.eps_min), BIG)
        v = float(np.interp(y, self.y, e)) if len(self.y) > 1 else float(e[0])
        return math.inf if v >= BIG else v

    def predicts_stable(self, eps: float, y: float) -> bool:
        return eps > self.eps_at(y)


@dataclass(frozen=True)
class Prediction:
    boundaries: dict[tuple[str, str], Boundary]
    unavailable: str | None = None  # why there is no prediction
    # controller -> the grip verdict at the campaign's base setting (grip_data of
    # runtime.stability.saturation: verdict, first slip, traction_mu to set), or why not
    grip: dict[str, dict[str, object]] = field(default_factory=dict)


def grip_verdicts(campaign: Campaign, tgt: Target) -> dict[str, dict[str, object]]:
    """Every controller's saturation and grip verdict at the campaign's base setting (its
    experiment, the path's duration, the nominal robot): ``wmr stability``'s
    :func:`~runtime.stability.saturation.saturation_verdict`, simulated, the same verdict
    with the first slip (time, wheel, margin) and the ``traction_mu`` that keeps grip."""
    exp = replace(campaign.experiment, paths=replace(
        campaign.experiment.paths, circle_duration=campaign.duration))
    out: dict[str, dict[str, object]] = {}
    for ctrl in campaign.controllers:
        try:
            v = saturation_verdict(tgt.setup.code, ctrl, campaign.formulation, tgt.nominal,
                                   exp, simulate=True)
        except ValueError as exc:
            out[ctrl] = {"verdict": "not checked", "line": f"not available ({exc})"}
            continue
        out[ctrl] = grip_data(v)
    return out


def y_grid(campaign: Campaign, base: float) -> list[float]:
    """The points of the map's y parameter where the boundary is computed."""
    dist = dict(campaign.vary).get(campaign.map_y)
    if dist is None or dist.choices:
        values = [float(c) for c in dist.choices] if dist is not None else [base]
        return sorted(set(values))
    lo, hi = dist.bounds(base)
    grid = np.linspace(lo, hi, campaign.map_grid)
    if dist.step is not None:
        grid = np.unique(np.round(grid / dist.step) * dist.step)
    return [float(f"{g:.12g}") for g in grid]


def velocities(campaign: Campaign) -> list[str]:
    dist = dict(campaign.vary).get("sensing.velocity")
    if dist is None:
        return [campaign.experiment.sensing.velocity]
    return [str(c) for c in dist.choices]


def predict(campaign: Campaign, tgt: Target) -> Prediction:
    """ε_min on the map for every controller and sensing model of the campaign."""
    from runtime.stability.analysis import analyse
    from runtime.stability.sampled_loop import covers, refusal

    code = tgt.setup.code
    grip = grip_verdicts(campaign, tgt)
    if not covers(code):
        return Prediction({}, unavailable=(
            f"robot '{tgt.name}': the sampled-data analysis needs the root's pose as the "
            "first coordinates, so no boundary is predicted"), grip=grip)

    section, _, key = campaign.map_y.partition(".")
    base_y = float(getattr(getattr(campaign.experiment, section), key))
    ys = y_grid(campaign, base_y)
    out: dict[tuple[str, str], Boundary] = {}
    exp0 = replace(campaign.experiment, paths=replace(
        campaign.experiment.paths, circle_duration=campaign.duration))
    for velocity in velocities(campaign):
        for ctrl in campaign.controllers:
            if refusal(code.controller(ctrl)):
                continue
            eps_min = []
            for y in ys:
                exp = with_values(exp0, {campaign.map_y: y, "sensing.velocity": velocity})
                a = analyse(code, ctrl, campaign.formulation, tgt.nominal, exp)
                numerator = a.gain_at_setting * a.eps
                if a.radius_without_switching >= 1.0:
                    eps_min.append(math.inf)
                elif numerator == 0 or math.isinf(a.max_stable_gain):
                    eps_min.append(0.0)
                else:
                    eps_min.append(numerator / a.max_stable_gain)
            out[(ctrl, velocity)] = Boundary(ctrl, velocity, tuple(ys), tuple(eps_min))
    return Prediction(out, grip=grip)
