"""The jitter budget's sequences replayed in the closed loop (``runtime.stability.jitter.replay``,
issue 46 item 4): Drishti, TDC, minimal formulation, sample-instant rates, h = 0.1 s, no
nominal delay, a 10 s circle, the timing given sample by sample (``runtime.sim.timing``).

* At the proved budget of docs/STABILITY.md's table (latencies in [0, 50 ms], "proved",
  ‖J‖_P ≤ 0.987 over the range, the gaps covered by the derived bound), on the MuJoCo
  engine: the adversarial search's worst
  sequence, the alternation of the smallest and largest latency and a random sequence of
  the two stay bounded (the last third's error no larger than the middle third's, and
  below 0.01);
* beyond the constant-delay boundary (64 ms), at [0, 80 ms]: the sequence the search finds
  (the same alternation, 0 and 80 ms) diverges on the model plant (‖(e, ė)‖ past 100,
  still growing) and on the engine (so the replay can fail the first test);
* a given timing is what the loop runs: a constant (h, 0) is the experiment's run bit for
  bit (one code path with the drawn timing), a latency or a period that differs changes it.
"""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import numpy as np
import pytest

from runtime.bindings.generated import load_robot_code
from runtime.experiment.settings import Experiment
from runtime.plants import plant_for
from runtime.sim import loop, paths
from runtime.sim.timing import GivenTiming
from runtime.stability import jitter as jt
from runtime.stability.sampled_loop import ClosedLoop, setting

CODE = load_robot_code("")
ROBOT = dict(CODE.params)
H = 0.1
BUDGET = 0.05  # s: the table's proved jitter for this loop
BASE = replace(Experiment(), sensing=replace(Experiment().sensing, velocity="sample-instant"))
MUJOCO = replace(BASE, plant=replace(BASE.plant, model="mujoco"))


@cache
def closed() -> ClosedLoop:
    return jt.loop_for(setting(CODE, "tdc", "minimal", ROBOT, BASE), tail=400)


@cache
def search(j: float) -> jt.Search:
    return jt.adversarial(closed(), 0.0, jt.delay_jitter(H, 0.0, j))


def replay(exp: Experiment, sequence: tuple[tuple[float, float], ...]) -> jt.Replay:
    return jt.replay(CODE, "tdc", "minimal", ROBOT, exp, sequence)


def test_sequences_inside_the_proved_budget_stay_bounded_on_mujoco() -> None:
    assert jt.verdict(closed(), 0.0, jt.delay_jitter(H, 0.0, BUDGET)).verdict == "proved"
    rng = np.random.default_rng(46)
    sequences = [search(BUDGET).sequence, ((H, 0.0), (H, BUDGET)),
                 tuple((H, float(d)) for d in rng.choice([0.0, BUDGET], size=37))]
    for seq in sequences:
        r = replay(MUJOCO, seq)
        assert r.plant == "mujoco" and r.run.failed_at is None
        assert not r.diverged and r.growth <= 1.0, (seq, r.growth)
        assert float(r.run.error_norm[2 * len(r.run.error_norm) // 3:].max()) < 0.01


@pytest.mark.parametrize("exp", [BASE, MUJOCO], ids=["model", "mujoco"])
def test_the_destabilising_sequence_diverges(exp: Experiment) -> None:
    found = search(0.08)
    assert found.rate > 1.0
    assert set(found.sequence) == {(H, 0.0), (H, 0.08)}
    r = replay(exp, found.sequence)
    # ‖(e, ė)‖ a hundred times DIVERGED (the engine's saturates there, the robot thrown)
    assert r.diverged and float(r.run.error_norm.max()) > 100.0, r.run.error_norm.max()
    if exp.plant.model == "generated":  # the model's keeps growing: ×10 per third
        assert r.growth > 10.0, r.growth


def test_the_given_timing_is_what_the_loop_runs() -> None:
    lin = replace(BASE, paths=replace(BASE.paths, circle_duration=3.0))
    ref = paths.circle(CODE, ROBOT, lin)

    def run(timing: GivenTiming | None) -> loop.Run:
        return loop.run(CODE, "tdc", "minimal", ref, ROBOT, lin,
                        plant=plant_for(CODE, lin, ROBOT), timing=timing)

    drawn = run(None)
    assert np.array_equal(run(GivenTiming(((H, 0.0),))).q, drawn.q)
    assert not np.allclose(run(GivenTiming(((H, 0.02),))).tau_applied, drawn.tau_applied)
    assert not np.allclose(run(GivenTiming(((0.12, 0.0), (0.08, 0.0)))).q, drawn.q)


def test_a_bad_timing_is_refused() -> None:
    with pytest.raises(ValueError, match="at least one"):
        GivenTiming(())
    with pytest.raises(ValueError, match="period > 0"):
        GivenTiming(((0.0, 0.01),))
