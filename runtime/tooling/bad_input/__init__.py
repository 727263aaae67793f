"""Every bad input tried on the generated C controllers, and what each one did.

``python -m runtime.tooling.bad_input.table`` runs all cases on the double build of
``generated/c`` (through cffi) and writes ``docs/BAD_INPUT.md``; ``--check`` exits 1 if
the committed file differs. ``tests/firmware/test_firmware_bad_input.py`` runs the same cases,
asserts each expectation and that the committed document equals :func:`render`'s output,
so the table cannot drift from the code.

A case runs on every controller it applies to, in both formulations. Each run: two
controllers with the same configuration take the same ``WARMUP`` valid steps; one then
gets the bad input (τ pre-filled with a sentinel). Recorded: the status, whether the
state's bytes and τ are unchanged, for a bad configuration also ``_init`` (on a
pattern-filled state) and ``_check_config``, and whether the next valid step (status,
τ and every state field) equals the twin's, which never saw the bad input.

Modules: :mod:`.cases` (every bad input and the base configuration), :mod:`.runner`
(running a case on a controller, checking the outcome), :mod:`.table` (``docs/BAD_INPUT.md``
and the command line).
"""
