"""Reading back the per-trial records of a results folder, for the scripts that compare or study benchmark runs.

A results folder (``slax-drake benchmark --out``) holds one JSON object per finished trial:
``<folder>/trials/<policy>/<DD>_<IIII>.json`` for the shelf simulator's Table I trials
(:mod:`slax_drake.evaluation.table1`) and ``<folder>/physics_trials/<policy>/<DD>_<IIII>.json`` for the Drake physics
benchmark (:mod:`slax_drake.evaluation.physics`); DD is the object count, IIII the scene index. Here a file is only
checked to be a JSON object: which fields a record must hold is up to its reader.
"""

from __future__ import annotations

import json
from pathlib import Path

from slax_drake.errors import UserError

KINDS = ("trials", "physics_trials")


def read_trial_records(folder, policy: str, kind: str = "trials", missing_ok: bool = False) -> dict[str, dict]:
    """{file stem, e.g. "04_0001": record} of every ``<folder>/<kind>/<policy>/*.json``, sorted by stem.

    ``kind``: "trials" (shelf simulator) or "physics_trials" (Drake physics benchmark). A file that is not valid
    JSON, or not a JSON object, is a UserError naming it. A missing ``<folder>/<kind>/<policy>`` folder is a
    UserError naming it, or no records with ``missing_ok``."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, not {kind!r}")
    policy_folder = Path(folder) / kind / policy
    if not policy_folder.is_dir():
        if missing_ok:
            return {}
        raise UserError(f"{policy_folder}: no such folder")
    records = {}
    for path in sorted(policy_folder.glob("*.json"), key=lambda path: path.stem):
        try:
            record = json.loads(path.read_bytes())
        except ValueError as e:  # json.JSONDecodeError, or bytes that are no text
            raise UserError(f"{path}: not valid JSON ({e})") from None
        if not isinstance(record, dict):
            raise UserError(f"{path}: not a trial record (a JSON object)")
        records[path.stem] = record
    return records


def analyse_trial_records(folder, policy: str, analyse, kind: str = "trials") -> tuple[dict, dict]:
    """(the records of :func:`read_trial_records`, {file stem: ``analyse(record)``}). A record that lacks what
    ``analyse`` reads (a KeyError, TypeError or ValueError from it) is a UserError saying so, and so is a folder with
    no record of ``policy``."""
    records = read_trial_records(folder, policy, kind)
    try:
        results = {key: analyse(record) for key, record in records.items()}
    except (KeyError, TypeError, ValueError) as e:
        trial = "a physics trial" if kind == "physics_trials" else "a trial"
        raise UserError(f"a trial record lacks what {trial} holds ({e!r})") from None
    if not records:
        raise UserError(f"no trial files of {policy}")
    return records, results


def without_keys(record, keys):
    """``record`` (a trial record's JSON value) with every dict entry whose key is in ``keys`` dropped, at any depth
    (e.g. the clock's readings, which differ between two runs of the same trial)."""
    if isinstance(record, dict):
        return {k: without_keys(v, keys) for k, v in record.items() if k not in keys}
    if isinstance(record, list):
        return [without_keys(v, keys) for v in record]
    return record
