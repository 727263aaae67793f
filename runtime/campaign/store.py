"""The output folder of a campaign: nothing finished is lost, nothing is counted twice.

    OUT/campaign.json             the campaign (its payload) and its SHA-256 identity
    OUT/parts/part-NNNNNNNN.parquet  the records of one finished task (first run index)
    OUT/results.parquet           every record, sorted by run index (rewritten at the end)

A part is written to a temporary name and renamed: a killed campaign leaves whole parts only.
On restart the finished run indices are read from the parts and only the missing ones run;
a folder holding a campaign of another identity is refused.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from runtime.campaign.spec import Campaign, field_type

SPEC_FILE = "campaign.json"
PARTS = "parts"
RESULTS = "results.parquet"


class CampaignFolderError(ValueError):
    """An output folder a campaign cannot resume into; the message says why."""


def schema(campaign: Campaign) -> pa.Schema:
    """The columns of every record (drawn parameters as ``p.NAME``)."""
    cols: list[tuple[str, pa.DataType]] = [
        ("index", pa.int64()), ("seed", pa.int64()), ("controller", pa.string()),
        ("formulation", pa.string()), ("path", pa.string()), ("status", pa.string()),
        ("status_code", pa.int64()), ("error", pa.string()), ("stable", pa.bool_()),
        ("rms_error", pa.float64()), ("max_error", pa.float64()), ("final_error", pa.float64()),
        ("rms_torque", pa.float64()), ("max_torque", pa.float64()), ("chatter", pa.float64()),
        ("median_gain", pa.float64()), ("failed_at", pa.float64()),
        ("saturated_steps", pa.int64()),
    ]  # fmt: skip
    types = {"int": pa.int64(), "float": pa.float64(), "str": pa.string()}
    cols += [(f"p.{name}", types[field_type(name)]) for name, _ in campaign.vary]
    return pa.schema(cols)


def check_folder(out: Path, campaign: Campaign) -> None:
    """Raise ``CampaignFolderError`` if ``out`` holds a campaign of another identity (writes
    nothing)."""
    spec = out / SPEC_FILE
    if spec.exists():
        try:
            recorded = json.loads(spec.read_text(encoding="utf-8"))
            old = recorded["sha256"]
        except (OSError, ValueError, KeyError) as exc:
            raise CampaignFolderError(f"--out {out}: unreadable {SPEC_FILE} ({exc})") from None
        digest = campaign.digest()
        if old != digest:
            raise CampaignFolderError(
                f"--out {out}: holds a campaign of another spec (sha256 {old[:12]}…, this one "
                f"{digest[:12]}…); resume with the same spec and robot or use another --out")


def prepare(out: Path, campaign: Campaign) -> set[int]:
    """Record the campaign in ``out`` (or check it is the one recorded there) and return
    the indices of the runs already finished."""
    spec = out / SPEC_FILE
    digest = campaign.digest()
    check_folder(out, campaign)
    if not spec.exists():
        atomic_write_text(spec, json.dumps({"sha256": digest, "campaign":
                                            campaign.to_payload()}, indent=2, sort_keys=True))
    (out / PARTS).mkdir(exist_ok=True)
    for stale in (out / PARTS).glob(".*.tmp"):  # a kill during a write: never renamed
        stale.unlink()
    return finished_indices(out)


def atomic_write_text(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


def part_files(out: Path) -> list[Path]:
    return sorted((out / PARTS).glob("part-*.parquet"))


def finished_indices(out: Path) -> set[int]:
    done: set[int] = set()
    for part in part_files(out):
        done.update(pq.read_table(part, columns=["index"]).column("index").to_pylist())
    return done


def write_part(out: Path, records: list[dict[str, Any]], sch: pa.Schema) -> Path:
    """One task's records as a Parquet part, atomically; named by its first run index."""
    first = min(int(r["index"]) for r in records)
    path = out / PARTS / f"part-{first:08d}.parquet"
    tmp = path.with_name(f".{path.name}.tmp")
    table = pa.Table.from_pylist(records, schema=sch)
    pq.write_table(table, tmp)
    os.replace(tmp, path)
    return path


def read_results(out: Path, sch: pa.Schema) -> pa.Table:
    """Every finished record, sorted by run index (each index once)."""
    tables = [pq.read_table(p, schema=sch) for p in part_files(out)]
    if not tables:
        return sch.empty_table()
    table = pa.concat_tables(tables).sort_by("index")
    idx = table.column("index").to_pylist()
    keep = [i for i in range(len(idx)) if i == 0 or idx[i] != idx[i - 1]]
    return table.take(keep) if len(keep) != len(idx) else table


def write_results(out: Path, table: pa.Table) -> Path:
    path = out / RESULTS
    tmp = path.with_name(f".{path.name}.tmp")
    pq.write_table(table, tmp)
    os.replace(tmp, path)
    return path
