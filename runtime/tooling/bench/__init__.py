"""``python -m runtime bench`` (``make bench``): our generated code against CasADi's
generated C, plain SymPy C, hand-written C and NumPy, all measured in one run.

C: one executable holds every variant (our double and float32 builds — the float objects'
symbols renamed — CasADi's ``CodeGenerator`` output, ``sympy.ccode`` after ``cse``, and
hand-written C) so they share one process, one compiler (gcc -O2) and one input table.
Each case: median, min and max over ``repeats`` repetitions of ``calls`` calls cycling
through 256 pre-generated input sets through a function pointer, outputs summed into a
printed checksum so nothing can be hoisted or removed.

Writes ``BENCHMARKS.md`` and ``benchmarks.json`` at the repository root.

Modules: :mod:`.c_variants` (the functions, their inputs and the C of each variant),
:mod:`.c_bench` (one executable for all of them, run and summarised),
:mod:`.step_bench` (the complete TDROC step against the hand-written one),
:mod:`.robot_c_bench` (every shipped robot's functions against CasADi's C, the trailer's
forward dynamics against hand-written C),
:mod:`.scale` (how cost grows with the robot),
:mod:`.python_timings` (Python variants and cold-start toolchain times), :mod:`.op_counts`
(CasADi's operation counts), :mod:`.report` (the reports and the command line).
"""
