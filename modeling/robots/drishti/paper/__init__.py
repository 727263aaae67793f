"""The paper's printed equations, transcribed, and a verdict on each against the derivation.

The specification (Roy et al. 2017) reaches us as a text extraction that lost almost every
minus sign and flattened sub- and superscripts (docs/PAPER.md items 1 and 2). A printed
equation is therefore never evidence by itself: this package transcribes each of
(1)–(14), (31) and the lumped relations for m, I and K *as best read*, and lets the
derivation of :mod:`modeling.robots.drishti.model` decide. One module per job, each using
only the ones above it:

``symbols``         the paper's letters (the model's symbols under their printed names, λ,
                    the printed auxiliaries Ω, k and the shorthands of (10)–(14))
``display``         text/LaTeX names, grouping in the printed terms, SI units (no
                    mathematics is decided there)
``transcriptions``  the printed equations as read, with sign slots, beside the derived
                    forms they are compared with; the printed parameter values
``signs``           the judge: solve the sign slots, compare, write the evidence
``verdicts``        every transcription judged: ``judgements()``, ``verdicts()``,
                    ``verdict_table()``

Only the derived side comes from the engine; nothing here is hand-derived. Running
``verdicts.verdicts()`` takes about three seconds (the engine's derivation dominates).
Drishti's ``MODEL.md`` (:mod:`modeling.robots.drishti.report`) shows the outcome.
"""
