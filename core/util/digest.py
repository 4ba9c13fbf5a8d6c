"""SHA-256 digests of a plan's files and inputs: plan.json records them when the plan is written
(core.output.files.write_plan) and ``bladecam verify`` compares them, so that a file changed after
planning is found whatever changed in it."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

_CHUNK = 1 << 20


def file_digest(path: str | Path) -> str:
    """The SHA-256 of a file's bytes, hex."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while chunk := f.read(_CHUNK):
            h.update(chunk)
    return h.hexdigest()


def inputs_digest(inputs: dict) -> str:
    """The SHA-256 of plan.json's "inputs" (keys sorted, compact JSON), hex."""
    return hashlib.sha256(json.dumps(inputs, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def plan_digests(folder: Path, names, inputs: dict, sources: list[str]) -> dict:
    """plan.json's "sha256": the digests of the folder's files ``names`` (plan.json aside), of its
    inputs, and of the blade's source files ``sources`` (absolute paths; the sample has none)."""
    return {"files": {name: file_digest(folder / name) for name in sorted(names) if name != "plan.json"},
            "inputs": inputs_digest(inputs),
            "sources": {p: file_digest(p) for p in sources if Path(p).is_file()}}
