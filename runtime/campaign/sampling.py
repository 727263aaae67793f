"""Each run's parameters from (campaign seed, run index) alone.

Run i draws from ``numpy.random.SeedSequence(seed, spawn_key=(i,))``: the same i gives the
same parameters whichever worker runs it, in whichever order, on a resumed campaign or not.
Parameters are drawn in the sorted order of their names.
"""

from __future__ import annotations

import math

import numpy as np

from runtime.campaign.spec import Campaign, Distribution, Value, field_type


def seed_sequence(seed: int, index: int) -> np.random.SeedSequence:
    return np.random.SeedSequence(seed, spawn_key=(index,))


def run_seed(seed: int, index: int) -> int:
    """The 32-bit seed recorded with run ``index`` (the first word of its SeedSequence)."""
    return int(seed_sequence(seed, index).generate_state(1)[0])


def controller_of(campaign: Campaign, index: int) -> str:
    """Controllers take turns: run i uses controllers[i mod their number]."""
    return campaign.controllers[index % len(campaign.controllers)]


def draw_one(dist: Distribution, base: Value, rng: np.random.Generator, kind: str) -> Value:
    """One value of ``dist`` about ``base`` (the experiment's or robot's own value)."""
    if dist.choices:
        value: Value = dist.choices[int(rng.integers(len(dist.choices)))]
        if isinstance(value, str):
            return value
    else:
        u = float(rng.random())
        if dist.spread is not None:
            value = float(base) * (1 + dist.spread * (2 * u - 1))
        else:
            assert dist.low is not None and dist.high is not None
            if dist.log:
                value = math.exp(math.log(dist.low) + u * math.log(dist.high / dist.low))
            else:
                value = dist.low + u * (dist.high - dist.low)
    if dist.step is not None:
        value = round(float(value) / dist.step) * dist.step
        value = float(f"{value:.12g}")  # 0.1 + 0.005 k printed as such, not 0.10500000000001
    return round(float(value)) if kind == "int" else float(value)


def base_values(campaign: Campaign, robot: dict[str, float],
                physical: dict[str, float] | None = None) -> dict[str, Value]:
    """The value each drawn parameter has before drawing (``physical``: the robot file's
    physical quantities, for ``physical.KEY``)."""
    out: dict[str, Value] = {}
    for name, _ in campaign.vary:
        section, _, key = name.partition(".")
        if section == "physical":
            out[name] = (physical or {})[key]
            continue
        out[name] = robot[key] if section == "robot" else getattr(
            getattr(campaign.experiment, section), key)
    return out


def draw(campaign: Campaign, index: int, base: dict[str, Value]) -> dict[str, Value]:
    """Run ``index``'s drawn parameters, by name."""
    rng = np.random.default_rng(seed_sequence(campaign.seed, index))
    return {name: draw_one(dist, base[name], rng, field_type(name))
            for name, dist in campaign.vary}
