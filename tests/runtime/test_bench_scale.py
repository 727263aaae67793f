"""The scaling benchmark's measuring parts (``runtime/tooling/bench/scale.py``): what
they read and count is checked here; the numbers themselves are ``make bench``'s."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from runtime.tooling.bench import scale

ROOT = Path(__file__).resolve().parents[2]


def test_operation_summaries_are_summed() -> None:
    assert scale.operations("145 add, 251 mul, 27 div, 4 sin/cos, 1 sqrt, 1 cmp, 1 fmax") == 430
    assert scale.operations("0 add, 0 mul") == 0


def test_tdroc_step_counts_the_kernels_a_step_calls() -> None:
    """The trailer's step evaluates M̂(q) once (it depends on the hitch angle) and ‖M̂⁻¹‖,
    (17) and the law from it; Drishti's minimal step evaluates no M̂ (its ‖M̂⁻¹‖ is
    computed at _init); no paper-form kernel counts."""
    def kernels(robot: str) -> list[str]:
        folder = scale.generated_folder(ROOT, robot)
        table = dict(scale.OP_ROW.findall((folder / "MODEL.md").read_text()))
        return scale.tdroc_step_kernels(folder, scale.prefix_of(folder), table)

    assert kernels("trailer") == ["minimal_mhat", "minimal_minv_norm_mhat",
                                  "minimal_omega_difference", "minimal_tde_mhat",
                                  "minimal_tdroc_law_mhat", "tdroc_weighted_gain"]
    drishti = kernels("drishti")
    assert "minimal_minv_norm" not in drishti and "minimal_tdroc_law" in drishti
    assert not any(k.startswith("paper_") for k in drishti)


def test_tdroc_step_counts_each_kernels_per_step_part() -> None:
    """A kernel's parameter-only part runs at _init (its ``_keep``): the step count reads
    the per-step part ``<prefix>_kernels.h`` documents, not the whole function (the
    trailer's ``minimal_mhat``: 17 operations a step, 160 with the coefficients its _init
    keeps)."""
    folder = scale.generated_folder(ROOT, "trailer")
    per_step = scale.step_operations(folder, "trailer")
    table = dict(scale.OP_ROW.findall((folder / "MODEL.md").read_text()))
    assert scale.operations(per_step["minimal_mhat"]) == 17
    assert scale.operations(per_step["minimal_mhat_keep"]) > 100
    assert scale.operations(table["minimal_mhat"]) > 100
    rung = scale.Rung("trailer", 1, 8)
    scale.measure_operations(folder, rung)
    kernels = scale.tdroc_step_kernels(folder, "trailer", table)
    assert rung.tdroc_step_ops == sum(scale.operations(per_step[k]) for k in kernels)


def test_step_signature_gives_the_sizes() -> None:
    assert scale.coordinates(scale.generated_folder(ROOT, "trailer3"), "trailer3") == (14, 2)
    assert scale.coordinates(scale.generated_folder(ROOT, "drishti"), "wmr") == (5, 2)


def test_peak_memory_is_the_childs_own() -> None:
    """A child that touches 150 MB reports at least that; a small one after it does not
    inherit the figure (os.wait4's rusage is per child)."""
    big = "b = bytearray(150 * 1024 * 1024); b[::4096] = b'x' * len(b[::4096])"
    peak = scale.run_with_peak([sys.executable, "-c", big], ROOT).peak_mb
    # The measuring process itself is large (a pytest worker can be 300 MB): a child forked
    # from it must not report the parent's pages as its own.
    ballast = bytearray(200 * 1024 * 1024)
    ballast[::4096] = b"x" * len(ballast[::4096])
    small = scale.run_with_peak([sys.executable, "-c", "pass"], ROOT).peak_mb
    del ballast
    assert peak > 150 and small < 100, (peak, small)


def test_cpu_time_is_the_childs() -> None:
    """A child that spins for 0.3 s of CPU reports about that, sleeping does not count."""
    spin = "import time\nt = time.process_time()\nwhile time.process_time() - t < 0.3: pass"
    busy = scale.run_with_peak([sys.executable, "-c", spin], ROOT)
    idle = scale.run_with_peak([sys.executable, "-c", "import time; time.sleep(0.3)"], ROOT)
    assert 0.3 <= busy.cpu_s < 1.5 and idle.cpu_s < 0.2, (busy, idle)
    assert idle.seconds >= 0.3


def test_a_failing_command_is_reported() -> None:
    with pytest.raises(RuntimeError, match="failed"):
        scale.run_with_peak([sys.executable, "-c", "raise SystemExit(3)"], ROOT)


def test_step_harness_runs_every_robot_and_agrees_across_builds(tmp_path: Path) -> None:
    """The x86 step harness builds for a robot, steps it without error and gives the same
    torques on each run (the timing compares like with like)."""
    exe = scale.build_step(scale.generated_folder(ROOT, "trailer2"), tmp_path)
    (ns1, check1), (ns2, check2) = scale.step_times([exe, exe], rounds=1)
    assert check1 == check2 and float(check1) != 0.0
    assert 0 < ns1 < 1e6 and 0 < ns2 < 1e6


def test_trailers_are_the_towed_bodies_of_the_robot_file() -> None:
    assert [scale.trailers(ROOT, r) for r in scale.SCALING] == [0, 1, 2, 3, 5]


def _rung(robot: str, carts: int, ops: int) -> scale.Rung:
    rung = scale.Rung(robot, carts, 5 + 3 * carts)
    rung.forward_dynamics_ops = rung.minimal_forward_dynamics_ops = ops
    rung.contact_forces_ops = rung.tdroc_step_ops = ops
    return rung


def test_growth_is_per_added_cart_and_flatness_is_judged() -> None:
    """Linear cost (100 a cart) is flat, with the three-to-five gap averaged over its two
    carts; the quadratic growth of the staged code (a cart costs more than the last) is
    not; Drishti (no cart) takes no part."""
    linear = [_rung("drishti", 0, 7), *[_rung(f"t{n}", n, 50 + 100 * n) for n in (1, 2, 3, 5)]]
    found = scale.growth(linear)
    assert [g.figure for g in found] == [f for f, _ in scale.GROWTH_FIGURES]
    assert found[0].steps == ((1, 2, 100.0), (2, 3, 100.0), (3, 5, 100.0))
    assert all(g.flat for g in found)
    quadratic = [_rung(f"t{n}", n, 40 * n * n) for n in (1, 2, 3, 5)]
    g = scale.growth(quadratic)[0]
    assert [s[2] for s in g.steps] == [120.0, 200.0, 320.0] and not g.flat
    assert "| no |" in "\n".join(scale.growth_section(quadratic))


def test_budgets_are_issue_51s_and_a_miss_is_shown() -> None:
    t5 = _rung("train5", 5, 1000)
    t5.model_cpu_s, t5.model_peak_mb, t5.c_bytes = 61.0, 180.0, 999_000
    t5.m4_tdroc_code, t5.m4_tdroc_stack, t5.x86_step_ns = 15_000, None, 900.0
    t2 = _rung("trailer2", 2, 100)
    t2.c_bytes = 500_000
    met = {b.what: b.met for b in scale.budgets([t2, t5])}
    assert met["train5 `wmr model` CPU"] is False and met["train5 generated C"] is True
    assert met["trailer2 generated C"] is False  # < 500 kB is strict
    assert met["train5 M4 TDROC stack"] is None and met["train5 x86 TDROC step"] is True
    text = "\n".join(scale.budget_section([t2, t5]))
    assert "| train5 `wmr model` CPU | 61.0 s | 60 s | **no** |" in text
    assert "not measured" in text
