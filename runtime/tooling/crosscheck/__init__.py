"""``python -m runtime crosscheck``: every implementation against the hand-written equations.

Reference: ``runtime/handwritten`` (the paper's equations typed by hand in NumPy,
independent of modeling/ and codegen/). Compared with it, on identical inputs:

* ``gen-python`` — generated/python (``wmr_model`` functions, ``controllers`` classes);
* ``C double``  — generated/c compiled with cffi (``runtime.cbuild``, cached under build/);
* ``CasADi``    — generated/casadi/*.casadi (model functions, and the law kernels — TDE,
  TDROC gain, the four laws — fed the inputs the reference computed in each step);
* ``C float32`` — generated/c built with -DWMR_FLOAT32.

Inputs: random samples for the model functions; for the controllers, measurement sequences
from a closed-loop run (the hand-written controller driving the generated Python forward
dynamics + kinematics with perturbed "true" parameters, RK4) and from random smooth motions
with random configurations (random nominal parameters, per-coordinate gains, window,
discount, estimator, bounds, a torque limit that saturates). Each controller sees the
recorded measurement sequence open loop, runs its own state machine and is compared step by
step (τ, switching gain, ‖s‖, Ĥ1, ‖u₁₋₃‖).

Deviation of a quantity: max over samples of ‖x − x_ref‖∞ / max(‖x_ref‖∞, 10⁻³·S), S the
largest ‖x_ref‖∞ of the sequence (the floor keeps near-zero samples from dominating).

Tolerances: 1e-9 for the double implementations. Float32 (see ``FLOAT32_TOL``) is compared
per step on identical inputs: inputs, parameters and the controller state are rounded to
float32 and the reference is evaluated on exactly those rounded values (in double), so the
deviation measures float32 arithmetic only, never the amplification of earlier differences
through the loop.

Exit status 1 if any deviation exceeds its tolerance. ``--perturb IMPL:KEY=FACTOR``
multiplies parameter KEY of the (nominal) parameters passed to IMPL (python, c64, c32,
casadi) by FACTOR: the check must then fail (used by the tests).

Modules: :mod:`.deviation` (the metric and tolerances), :mod:`.bindings` (calling the C
library and CasADi), :mod:`.inputs` (random samples and measurement sequences),
:mod:`.model_checks` (model functions and the derivation's self-consistency),
:mod:`.controller_runs` (each implementation stepped over a sequence),
:mod:`.controller_checks` (comparing the runs), :mod:`.report` (the tables and the verdict),
:mod:`.command` (``crosscheck()`` and the command line).
"""
