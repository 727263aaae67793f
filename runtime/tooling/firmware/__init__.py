"""The generated C on a Cortex-M4F: cross-build, sizes, stack, and an emulated TDROC run.

``python -m runtime.tooling.firmware.report [--out docs/FIRMWARE.md]`` (needs
``arm-none-eabi-gcc`` with newlib; the emulated run also needs ``unicorn``):

1. compiles every ``generated/c/wmr_*.c`` with :data:`ARM_FLAGS` (``-Werror``), float32
   (``-DWMR_FLOAT32``) and double, with ``-fstack-usage -fcallgraph-info=su``;
2. links, per controller, a tiny ``main`` (init + one step, float32) with newlib-nano
   (``--specs=nano.specs --specs=nosys.specs``, ``--gc-sections``) and lists the
   double-precision helper symbols in the ELF (``__aeabi_d*``, ``__aeabi_f2d``, ...:
   there must be none);
3. reports ``.text``/``.data``/``.bss`` per ELF (``arm-none-eabi-size``), and per
   generated function its code size (``nm -S``), its own frame (``.su``) and the
   worst-case stack through its callees: the call graph of ``-fcallgraph-info`` for
   generated code, and for library callees (``sinf``, ``memcpy``, ...) their frames
   and ``bl`` targets read from the linked ELF's disassembly (push/vpush/sub sp);
4. runs the float32 TDROC step (paper formulation) in the Unicorn emulator (Cortex-M4,
   FPU) on a recorded closed-loop sequence (the lawn-mower path through
   ``runtime.sim.loop.run(float32=True)``, ε = 0.5), and compares its torques with the
   host float32 build (in ulps) and the host double build; counts the instructions
   executed per step and measures the stack's high-water mark.

Everything is written to ``docs/FIRMWARE.md``.

Modules: :mod:`.build` (the toolchain, compiling and linking, step 1), :mod:`.symbols` and
:mod:`.stack` (sizes and the worst-case stack, step 3), :mod:`.emulator` (the Unicorn
harness) and :mod:`.emulated_run` (recording, replaying and comparing, step 4),
:mod:`.report` (``docs/FIRMWARE.md`` and the command line). :mod:`.compare_casadi`: the
same measurements for CasADi's generated C (``docs/FIRMWARE_VS_CASADI.md``).
"""
