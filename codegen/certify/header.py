"""The certificate as a comment in each generated header, read from the committed results.

``python -m codegen.backends.c.certify`` writes ``results/<robot>.json`` (it takes minutes);
``python -m codegen`` only reads it here: each function's documentation gains its box's
name, the certified bound per output and the no-overflow verdict, when the result's hash
of the printed program matches the program printed now, and says the result is stale
otherwise (the printing changed: run the command again). A robot with no results gets no
lines.
"""

from __future__ import annotations

import hashlib

from codegen.certify.stored import robot_results


def body_hash(body: object) -> str:
    """A hash of a function's printed body (the lowering's statement lines, from which the
    certified program is parsed): a result is stale when it changes."""
    return hashlib.sha256(repr(body).encode()).hexdigest()[:16]


def certificate_doc(name: str, body: object, prefix: str) -> list[str]:
    """The lines added to function ``name``'s header documentation (``body``: its printed
    statements; ``prefix``: the robot's, ``wmr``), empty without results."""
    results = {row["function"]: row for row in robot_results(prefix).get("functions", [])}
    row = results.get(name)
    if not results:
        return []
    head = "float32 (python -m codegen.backends.c.certify; box and method: docs/FLOAT32.md):"
    if row is None or row["hash"] != body_hash(body):
        return ["", head + " no current certificate (the printed code changed since the",
                "last run: run it again)."]
    per_arg: dict[str, float] = {}
    for out in row["outputs"]:
        arg = out["output"].split("[")[0].split("->")[0]
        per_arg[arg] = max(per_arg.get(arg, 0.0), out["bound"])
    bounds = ", ".join(f"{a} {b:.2g}" for a, b in per_arg.items())
    composed = row.get("composed", {}).get("function", "")
    if row["proved"] and composed:  # over its producer's image (certify/compose.py)
        verdict = (f"proved over its derived inputs as {composed} computes them in float32 "
                   f"from its declared box (its rounding included): no intermediate "
                   f"overflows or is NaN;")
    elif row["proved"]:
        verdict = "proved over its declared box: no intermediate overflows or is NaN;"
    else:
        verdict = f"NOT proved over its declared box ({row['reason']});"
    guards = (f" when it returns OK (it may return {', '.join(row['open_guards'])} there)"
              if row.get("open_guards") else "")
    lines = ["", head, f"{verdict} |float32 - exact| <= {bounds} (largest entry){guards}."]
    return _wrap(lines)


def _wrap(lines: list[str], width: int = 88) -> list[str]:
    out: list[str] = []
    for line in lines:
        words, cur = line.split(), ""
        if not words:
            out.append("")
            continue
        for w in words:
            if cur and len(cur) + 1 + len(w) > width:
                out.append(cur)
                cur = w
            else:
                cur = f"{cur} {w}" if cur else w
        out.append(cur)
    return out

