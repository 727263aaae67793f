"""How expressions become code: SymPy FunctionSpecs -> C99, NumPy-only Python, CasADi.

Input: :class:`codegen.spec.FunctionSpec` (a pure function whose outputs are final SymPy
expressions of its input symbols). Backends do no mathematics beyond common-subexpression
elimination and printing.

Shared pieces
    :mod:`codegen.spec`           the interface with ``modeling/`` (FunctionSpec, Argument, Field)
    :mod:`codegen.layout`         sizes, row-major field offsets, spec validation, local names
    :mod:`codegen.cse`            ``cse_function(spec) -> CseResult`` (one CSE over all outputs,
                                  temporaries ``_t0, _t1, ...``) and ``count_ops`` (the
                                  "operations after CSE: ..." line every function documents)
    :mod:`codegen.printer_base`   the printing structure shared by the C and Python printers
                                  and the op counter (so the counts are what is printed)
    :mod:`codegen.template_util`  the strict Jinja2 environment and the file preamble

Backends (each: ``config.py``, ``printer.py`` except CasADi, ``templates/``, ``render``)
    :mod:`codegen.backends.c`       ``render_all({module: specs}, config, source=)`` ->
                                    ``wmr_types.h`` + ``<module>.h``/``<module>.c``; C99,
                                    ``wmr_real_t`` double or float (``-DWMR_FLOAT32``);
                                    ``cdef(specs, float32=)`` for cffi
    :mod:`codegen.backends.python`  ``render(specs, module, config, source=)`` ->
                                    ``<module>.py`` (NumPy + math only)
    :mod:`codegen.backends.casadi`  ``to_casadi(spec) -> casadi.Function``;
                                    ``render(specs, module, config, source=)`` -> bytes of
                                    ``<name>.casadi`` (``Function.save``) + a text manifest;
                                    ``generate_c`` writes CasADi's own C for benchmarks

Every backend flattens an argument the same way: row-major, a params/struct argument as
its fields in order. Output is deterministic: same specs, byte-identical files, whatever
the hash seed.
"""
