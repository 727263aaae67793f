"""The committed results of ``python -m codegen.backends.c.certify``
(``results/<robot>.json``), read by the generated headers and MODEL.md; nothing here
imports a backend, so the generator may import it."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path
from typing import Any

from codegen.certify.runtime_check import checked_by

RESULTS_DIR = Path(__file__).resolve().parent / "results"


@cache
def robot_results(prefix: str) -> dict[str, Any]:
    for path in sorted(RESULTS_DIR.glob("*.json")):
        data = json.loads(path.read_text())
        if data.get("prefix") == prefix:
            return dict(data)
    return {}


def model_section(prefix: str) -> str:
    """The MODEL.md section of the robot with ``prefix`` ("" without results): the
    declared box and, per function, the certified bound and verdict, and the steps'
    torque bounds against tau_max, as the last ``python -m codegen.backends.c.certify``
    found them."""
    data = robot_results(prefix)
    if not data:
        return ""
    lines = [
        "", "## float32 certificate", "",
        "From `python -m codegen.backends.c.certify` (method, searches and ratios:",
        "docs/FLOAT32.md). Over the declared operating box (the parameters above within",
        "±10 %, angles within two turns, rates, torques and gains in the controllers'",
        "operating ranges: the box of each function is in `codegen/certify/results/`),",
        "|float32 − exact| per generated function (largest output) and whether no",
        "intermediate can overflow or be NaN:", "",
        "| function | certified bound | no overflow / NaN |", "|---|---|---|"]
    for row in data["functions"]:
        proved = "proved" if row["proved"] else f"not proved ({row['reason']})"
        lines.append(f"| `{row['function']}` | {row['bound']:.3g} | {proved} |")
    lines += ["", "Controller steps, torque per driven wheel (N m) against τ_max, with the",
              "errors the law's inputs carry from the rest of the step:", "",
              "| controller | formulation | torque bound | τ_max | holds |",
              "|---|---|---|---|---|"]
    for st in data.get("steps", []):
        reason = "; ".join(dict.fromkeys(st["reason"].split("; ")))
        check = checked_by(prefix, st["controller"])
        holds = "proved" if st["proved"] else (
            reason + (f" ({check})" if check else "")) if reason.startswith("if ") else (
            f"not proved ({reason})")
        lines.append(f"| {st['controller'].upper()} | {st['formulation']} | {st['bound']:.3g} "
                     f"| {st['tau_max']:g} | {holds} |")
    if any(not st["proved"] and checked_by(prefix, st["controller"])
           for st in data.get("steps", [])):
        lines += ["", "A conditional row (\"if ...\") holds for a step whose inputs are in the",
                  "declared box and after which the function it names returns `OK`: it",
                  "reads the state the step left (the switching gain, and for TDROC the",
                  "‖M̂⁻¹‖ and window difference norms (25) read) against the certificate's",
                  "boxes, rendered in the controller's header as `<PREFIX>_<CTRL>_CERT_*`;",
                  "no step calls it."]
    return "\n".join(lines) + "\n"
