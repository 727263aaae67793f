"""``python -m runtime crosscheck``: every implementation of every generated robot, compared.

Robots: every robot found under ``generated/`` (the root and each ``generated/<name>/``
with a ``python/robot.py``), or those named by ``--robot NAME_OR_DIR`` (:mod:`.targets`).
Each robot's section of the report names it (robot name, folder, C prefix).

**Against the hand-written equations** (the paper's robot only; :mod:`.handwritten_check`).
Reference: ``runtime/tooling/witness`` (the paper's equations typed by hand in NumPy,
independent of modeling/ and codegen/). Compared with it, on identical inputs:

* ``gen-python`` — the robot's generated Python (model functions, ``controllers`` classes);
* ``C double``  — its generated C compiled with cffi (``runtime.bindings.cbuild``, cached
  under build/);
* ``CasADi``    — its generated ``*.casadi`` (model functions, and the law kernels — TDE,
  TDROC gain, the four laws — fed the inputs the reference computed in each step);
* ``C float32`` — the generated C built with ``-D<PREFIX>_FLOAT32``.

Inputs: random samples for the model functions; for the controllers, measurement sequences
from a closed-loop run (the hand-written controller driving the generated Python forward
dynamics + kinematics with perturbed "true" parameters, RK4) and from random smooth motions
with random configurations (random nominal parameters, per-coordinate gains, window,
discount, estimator, bounds, a torque limit that saturates). Each controller sees the
recorded measurement sequence open loop, runs its own state machine and is compared step by
step (τ, switching gain, ‖s‖, Ĥ1, ‖u₁₋₃‖).

**Against the generated NumPy** (every robot; :mod:`.generated_check`). Every function of
the generated model, laws and plant modules, enumerated from the NumPy modules and the C
headers (:mod:`.generated_functions`), in C double, C float32 and CasADi at random
consistent states (q random, wheel rates random, the dependent velocities through the
generated kinematics); and every C controller (double, float32) against the generated
Python controller classes step by step along a closed loop (``runtime.sim.loop``) and
random near/far sequences (:mod:`.generated_controllers`).

Deviation of a quantity: max over samples of ‖x − x_ref‖∞ / max(‖x_ref‖∞, f·S), S the
largest ‖x_ref‖∞ of the sequence (the floor keeps near-zero samples from dominating),
f = 10⁻³ (10⁻² for float32 against the generated NumPy).

Tolerances: 1e-9 for the double implementations. Float32 (see ``FLOAT32_TOL``,
``GENERATED_FLOAT32_TOL``) is compared per step on identical inputs: inputs, parameters and
the controller state are rounded to float32 and the reference is evaluated on exactly those
rounded values (in double), so the deviation measures float32 arithmetic only, never the
amplification of earlier differences through the loop.

Exit status 1 if any deviation exceeds its tolerance. ``--perturb IMPL:KEY=FACTOR``
multiplies parameter KEY of the (nominal) parameters passed to IMPL (python, c64, c32,
casadi) by FACTOR: the check must then fail (used by the tests).

Modules: :mod:`.targets` (which robot, where its code is), :mod:`.deviation` (the metric
and tolerances), :mod:`.bindings` (calling the C library and CasADi); the hand-written
comparison: :mod:`.inputs` (random samples and measurement sequences), :mod:`.model_checks`
(model functions and the derivation's self-consistency), :mod:`.controller_runs` (each
implementation stepped over a sequence), :mod:`.controller_checks` (comparing the runs),
:mod:`.handwritten_check`; the comparison with the generated NumPy:
:mod:`.generated_functions`, :mod:`.generated_controllers`, :mod:`.generated_check`;
:mod:`.report` (the tables and the verdict), :mod:`.command` (``crosscheck()`` and the
command line).
"""
