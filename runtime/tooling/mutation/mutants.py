"""The mutants: realistic one-line bugs over modeling/, codegen/ and runtime/, each with the
tests meant to catch it (``python -m runtime.tooling.mutation`` runs them).

Each is a bug someone could write: a sign, a dropped term, a swapped extreme, ``and`` for
``or``, a check left out. A mutant the suite does not catch gets a test, or is argued
equivalent in the report that lists it (``runtime/tooling/mutation/README.md``).
"""

from __future__ import annotations

from runtime.tooling.mutation.engine import Mutant

STAGED = "modeling/staged.py"
LAGRANGE = "modeling/lagrange.py"
LOOP = "runtime/sim/loop.py"
TIMING = "runtime/sim/timing.py"
SENSORS = "runtime/sim/sensors.py"
FAULTS = "runtime/experiment/faults.py"
PAYLOAD = "runtime/sim/payload.py"
PATHS = "runtime/sim/paths.py"
OUTCOME = "runtime/sim/outcome.py"
RK4 = "runtime/sim/csrc/plant_rk4.c"
SAMPLED = "runtime/stability/sampled_loop.py"
SATURATION = "runtime/stability/saturation.py"
CHECKS = "runtime/stability/checks.py"
FREEZE = "runtime/commands/freeze.py"
MUJOCO_PLANT = "runtime/mujoco/plant.py"
STEP_BENCH = "runtime/tooling/bench/step_bench.py"
EXECUTION = "runtime/campaign/execution.py"
PRINTER = "codegen/printer_base.py"
SLIP = "runtime/sim/slip_monitor.py"
PLANAR = "modeling/importers/planar.py"
AUDIT = "modeling/audit.py"
TDROC_C = "generated/c/wmr_tdroc.c"
SETTINGS = "runtime/experiment/settings.py"
ANALYSIS = "runtime/stability/analysis.py"

T_STAGED = "tests/derivation/test_staged_solves.py"
T_KKT = "tests/derivation/test_derivation_kkt.py"
T_KANE = "tests/derivation/test_description_kane.py"
T_ROOT = "tests/derivation/test_root_frame.py"
T_FAULTS = "tests/runtime/test_faults.py"
T_FAULTS_MJ = "tests/runtime/test_faults_mujoco.py"
T_JITTER = "tests/runtime/test_jitter.py"
T_SENSING = "tests/runtime/test_sensing_estimator.py"
T_REPRO = "tests/reproduction/test_reproduction.py"
T_STAB = "tests/runtime/test_stability_any_robot.py"
T_SAT = "tests/runtime/test_saturation_payload.py"
T_FROZEN = "tests/firmware/test_frozen_config.py"
T_OUTCOME = "tests/runtime/test_outcome.py"
T_ONE_LOOP = "tests/runtime/test_one_loop.py"
T_GEN_SYMPY = "tests/generated/test_generated_vs_sympy.py"
T_MUJOCO = "tests/runtime/test_mujoco.py"
T_RK4 = "tests/runtime/test_plant_integrator.py"

MUTANTS: tuple[Mutant, ...] = (
    # --- modeling: the derivation ---------------------------------------------------------
    Mutant("ldlt-pivot", STAGED,
           "dj = a[j, j] - sum((lower[j, k] ** 2 * diag[k]",
           "dj = a[j, j] - sum((lower[j, k] * diag[k]",
           (T_STAGED,), "a wrong pivot in the LDLᵀ solve of a robot with > 3 wheel coordinates"),
    Mutant("lu-elimination-sign", STAGED,
           "lu[i, k] = self.define(lu[i, k] - factor * lu[j, k])",
           "lu[i, k] = self.define(lu[i, k] + factor * lu[j, k])",
           (T_STAGED,), "a wrong LU elimination for a constraint block of > 3 unknowns"),
    Mutant("lu-back-substitution", STAGED,
           "x[i, col] = self.define((y[i] - sum((lu[i, k] * x[k, col]",
           "x[i, col] = self.define((y[i] + sum((lu[i, k] * x[k, col]",
           (T_STAGED,), "a wrong back substitution in the staged LU"),
    Mutant("euler-lagrange-sign", LAGRANGE,
           "h.append(self.simplify(d_dt - sp.diff(t, qi) + sp.diff(self.potential_energy, qi)))",
           "h.append(self.simplify(d_dt + sp.diff(t, qi) + sp.diff(self.potential_energy, qi)))",
           (T_KKT, T_KANE), "H(q, q̇) of (9) with the wrong sign of ∂T/∂q"),
    Mutant("minimal-bias-drops-sdot", LAGRANGE,
           "return (s.T * (self.mass_matrix * self.null_space_rate + h)).applyfunc(self.simplify)",
           "return (s.T * h).applyfunc(self.simplify)",
           (T_KKT,), "the minimal form's H̄ without M Ṡ η (the null space's rate)"),
    Mutant("world-rotation-sign", LAGRANGE,
           "self.stage.define(s * a + c * b)",
           "self.stage.define(s * a - c * b)",
           (T_ROOT,), "a body-frame velocity rotated into the world wrongly"),
    Mutant("root-twist-transport", LAGRANGE,
           "rate[x] = stage.define(rate[x] - turn * v[y])",
           "rate[x] = stage.define(rate[x] + turn * v[y])",
           (T_ROOT, T_KANE), "the trailers' root-twist rate with its transport term's sign wrong"),
    # --- modeling: robot files -------------------------------------------------------------
    Mutant("ground-through-wheel-tops", PLANAR,
           "plan.ground = min(float(f.origin[2]) - geom.size[0] for geom, f in "
           "plan.cylinders.values())",
           "plan.ground = min(float(f.origin[2]) + geom.size[0] for geom, f in "
           "plan.cylinders.values())",
           ("tests/robot_files/test_import.py", "tests/robot_files/test_import_public.py"),
           "a file without a ground frame read with its ground through the wheels' tops"),
    Mutant("audit-unit-slip-lenient", AUDIT,
           "UNIT_SLIP = 1e3  # × what the mass and size allow",
           "UNIT_SLIP = 1e4  # × what the mass and size allow",
           ("tests/robot_files/test_audit.py", "tests/robot_files/test_import_published.py"),
           "an inertia typed in g m² (1,000×) passing the audit as kg m²"),
    # --- codegen ------------------------------------------------------------------------
    Mutant("printer-negative-half-power", PRINTER,
           "                return f\"{self.lit(1.0)}/{text if single else f'({text})'}\", False",
           "                return text, single",
           ("tests/codegen/test_codegen_backends.py", T_GEN_SYMPY),
           "x^(-3/2) printed as x^(3/2): the reciprocal dropped"),
    # --- generated: the firmware C's documented ranges ----------------------------------
    Mutant("tdroc-window-over-strict", TDROC_C,
           "if (config->n < 2 || config->n > WMR_MAX_WINDOW) {",
           "if (config->n < 3 || config->n > WMR_MAX_WINDOW) {",
           ("tests/firmware/test_controller_contract.py::"
            "test_accepted_inputs_never_give_a_nonfinite_output",),
           "TDROC's documented window n = 2 refused by the firmware"),
    # --- runtime: sensing, faults, payload, the loop ----------------------------------------
    Mutant("encoder-rounds", SENSORS,
           "counts = np.floor(angles * self.counts_per_rad)",
           "counts = np.round(angles * self.counts_per_rad)",
           (T_FAULTS, T_SENSING), "an encoder that rounds to the nearest count"),
    Mutant("encoder-average-over-window", SENSORS,
           'if v == "sample-instant":\n            return true_rates.copy()',
           'if v == "encoder-average":\n            return true_rates.copy()',
           ("tests/runtime/test_sensors.py", T_SENSING),
           "the encoder average read as the true instantaneous rate"),
    Mutant("fault-window-one-late", FAULTS,
           "k0 = max(1, math.ceil(self.start / h - tol))",
           "k0 = max(1, math.ceil(self.start / h - tol) + 1)",
           (T_FAULTS,), "every fault starting one sample late"),
    Mutant("traction-overlap-least", FAULTS,
           "loss[ks] = np.maximum(loss[ks], f.magnitude * w)",
           "loss[ks] = np.minimum(loss[ks], f.magnitude * w)",
           (T_FAULTS,), "overlapping traction losses keep the smaller one (the first: none)"),
    Mutant("torque-limit-overlap-largest", FAULTS,
           "limit[ks] = np.minimum(limit[ks], lim)",
           "limit[ks] = np.maximum(limit[ks], lim)",
           (T_FAULTS,), "overlapping torque limits keep the larger one (the first: none)"),
    Mutant("extra-payload-inverted", PAYLOAD,
           "    if pl.extra_on(t):\n        loads.append",
           "    if not pl.extra_on(t):\n        loads.append",
           (T_REPRO,), "the extra payload on board exactly when it is off"),
    Mutant("extra-payload-engine-always", PAYLOAD,
           "return np.array([pl.fixed_payload, pl.extra_payload if pl.extra_on(t) else 0.0])",
           "return np.array([pl.fixed_payload, pl.extra_payload])",
           ("tests/runtime/test_payload_schedule.py", T_FAULTS_MJ, T_MUJOCO),
           "the engine carrying the extra payload always"),
    Mutant("rk4-weight", RK4,
           "x[i] += dt / SIM_LIT(6.0) * (k1[i] + SIM_LIT(2.0) * k2[i] + SIM_LIT(2.0) * k3[i]",
           "x[i] += dt / SIM_LIT(6.0) * (k1[i] + SIM_LIT(2.0) * k2[i] + SIM_LIT(1.0) * k3[i]",
           (T_RK4,), "RK4 with a wrong weight: a first-order plant"),
    Mutant("jitter-not-drawn", TIMING,
           "d += float(self.rng.uniform(-self.jitter, self.jitter))",
           "d += 0.0 * float(self.rng.uniform(-self.jitter, self.jitter))",
           (T_JITTER,), "a loop that ignores the jitter it is given"),
    Mutant("latency-keeps-overtaken", LOOP,
           "if k < self.sent:\n                continue",
           "if k > self.sent:\n                continue",
           (T_ONE_LOOP, T_JITTER), "delayed commands never replacing the active one"),
    Mutant("circle-rates-swapped", PATHS,
           "return (v + rate * b / 2) / r, (v - rate * b / 2) / r",
           "return (v - rate * b / 2) / r, (v + rate * b / 2) / r",
           (T_STAB, T_REPRO), "the circle's wheel rates for the other turning direction"),
    Mutant("outcome-and-or", OUTCOME,
           "if not (final <= limit and rms <= limit):",
           "if not (final <= limit or rms <= limit):",
           (T_OUTCOME,), "a run that ends off the path called ok"),
    # --- runtime: verdicts --------------------------------------------------------------
    Mutant("jitter-upper-extreme", SAMPLED,
           "delays = sorted({max(0.0, s.delay - jitter), s.delay, s.delay + jitter})",
           "delays = sorted({max(0.0, s.delay - jitter), s.delay})",
           (T_JITTER,), "an unstable loop under jitter called stable"),
    Mutant("saturation-without-payload", SATURATION,
           'heavy = plant_parameters(code, nominal, exp, "payload" if plant == "payload" '
           "else plant)",
           'heavy = plant_parameters(code, nominal, exp, "nominal")',
           (T_SAT,), "the torque demand of the bare robot: saturation called ok"),
    Mutant("verdict-tolerates-radius", ANALYSIS,
           "        stable=radius < 1.0,\n",
           "        stable=radius < 1.01,\n",
           (T_STAB, T_JITTER), "a loop of spectral radius just above 1 called stable"),
    Mutant("slip-needs-least-wheel", SLIP,
           "return float(np.max(np.abs(forces) / n)) if np.all(n > 0) else math.inf",
           "return float(np.min(np.abs(forces) / n)) if np.all(n > 0) else math.inf",
           ("tests/runtime/test_slip_asymmetric.py", T_MUJOCO),
           "the friction needed read off the wheel that needs the least"),
    Mutant("contact-timeconst-one-step", SETTINGS,
           'if pl.model == "mujoco" and pl.contact_timeconst < 2 * dt:',
           'if pl.model == "mujoco" and pl.contact_timeconst < dt:',
           (T_MUJOCO,), "a contact MuJoCo stiffens silently, accepted"),
    Mutant("pre-run-check-skips-tde", CHECKS,
           "    if info.tde:\n        check_tde(",
           "    if not info.tde:\n        check_tde(",
           ("tests/reproduction/test_reproduce_refusal.py", T_STAB),
           "TDC/TDROC run where (17)'s condition fails"),
    Mutant("freeze-ignores-verdict", FREEZE,
           "chosen = next((v for v in verdicts if v[0] in candidates and v[2].stable), None)",
           "chosen = next((v for v in verdicts if v[0] in candidates), None)",
           (T_FROZEN,), "a configuration predicted unstable frozen into firmware"),
    Mutant("engine-ignores-traction-loss", MUJOCO_PLANT,
           "self.model.geom_friction[geom, 0] = self.contact.friction * (1.0 - float(loss))",
           "self.model.geom_friction[geom, 0] = self.contact.friction",
           (T_FAULTS_MJ,), "wmr faults --plant mujoco reporting traction rows fault-free"),
    Mutant("engine-ignores-torque-limit", MUJOCO_PLANT,
           "return [float(np.clip(tau[i], -lim[i], lim[i])) for i in range(self.nu)]",
           "return [float(tau[i]) for i in range(self.nu)]",
           (T_FAULTS_MJ,), "a torque-saturation fault that does nothing on the engine"),
    # --- tooling ------------------------------------------------------------------------
    Mutant("bench-times-disagreeing", STEP_BENCH,
           "    if (!(worst <= TOL * (scale > 1.0 ? scale : 1.0))) return 3;",
           "    (void)TOL;",
           ("tests/runtime/test_bench.py::test_step_benchmark_refuses_a_competitor_with_other_torques",),
           "make bench timing a competitor that computes other torques"),
    Mutant("campaign-connect-unbounded", EXECUTION,
           'client = Client(scheduler, timeout=f"{timeout}s")',
           "client = Client(scheduler)",
           ("tests/runtime/test_campaign.py::test_out_file_and_bad_spec_and_unreachable_scheduler",),
           "an unreachable scheduler waited for with Dask's default"),
)
