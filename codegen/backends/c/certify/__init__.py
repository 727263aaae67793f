"""A float32 certificate for the generated C: a proved error bound per output and a proof
that no intermediate overflows or is NaN, over a declared input box (issue 50).

* :mod:`.program`: the printed C body read back as a straight-line program, in the printed
  operation order (what the certificate and the search evaluate).
* :mod:`.analysis`: sound interval ranges and a rigorous error radius per operation
  (float32 unit roundoff 2^-24; sin/cos: the helpers' stated 2 ulp).
* :mod:`.bound`: box subdivision and the certificate.
* :mod:`.boxes`: the declared operating boxes.
* :mod:`.search`: random and coordinate search in numpy float32 against mpmath.
* :mod:`.robot`: all functions of one robot; ``python -m codegen.backends.c.certify`` the report.
"""
