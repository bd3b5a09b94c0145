"""The settings a benchmark folder's trials were made with, recorded once per folder, and the check that a resumed
run uses the same ones.

Every setting that changes a trial's outcome goes into ``<out>/settings.json`` (the physics benchmark:
``<out>/physics_settings.json``) before the first trial runs: the scenario's content (a SHA-256 of the parsed
scenario, less the fields that only choose *which* trials run: the protocol's seed, densities and scenes per
density), the protocol seed, the distribution model (perception), the target size, the observation mode (privileged
or camera, with its segmentation and sensor noise), the horizon per object, the suction cost, the visibility
threshold, the action-model rules (and the content of a reach map they name) and, per policy, its class and
constructor options (the physics benchmark adds the station file's content and object sleep). A run into a folder
recorded with other values is refused before anything runs, with one line naming the first setting that differs; a
policy new to the folder is added to the record.

The record also names the code that ran (``code``: slax-drake's version and, in a git checkout, the commit, with
"+changes" when tracked files differ from it; every distinct one that wrote into the folder, in order). It is not
compared: a default changed in the code (a segmenter's rule, an estimator's) shows there, not in the settings.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import subprocess
from pathlib import Path

from slax_drake.errors import PhysicsBenchmarkError, SettingsMismatchError
from slax_drake.io import write_text_atomic

SETTINGS_FILE = "settings.json"  # the Table I benchmark's record
PHYSICS_SETTINGS_FILE = "physics_settings.json"  # the physics benchmark's, beside it in the same folder


# Scenario fields added after folders were recorded, with their defaults (today's behaviour): left out of the digest
# while they hold the default, so that a folder recorded before they existed still resumes; any other value is
# hashed like every field.
LATER_SCENARIO_FIELDS = {("target", "placement"): "after-objects", ("protocol", "count_includes_target"): False}


def scenario_digest(scenario) -> str:
    """SHA-256 of ``scenario`` (a slax_drake.config.Scenario) as canonical JSON, less the protocol fields that only
    choose which trials run (seed, densities, scenes per density) and the later fields at their defaults
    (:data:`LATER_SCENARIO_FIELDS`)."""
    d = dataclasses.asdict(scenario)
    for key in ("seed", "densities", "scenes_per_density"):
        d["protocol"].pop(key, None)
    for (section, key), default in LATER_SCENARIO_FIELDS.items():
        if d[section].get(key) == default:
            d[section].pop(key, None)
    return hashlib.sha256(json.dumps(d, sort_keys=True).encode()).hexdigest()


def file_digest(path) -> str:
    """SHA-256 of a file's bytes."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


@functools.lru_cache(maxsize=1)
def code_version() -> str:
    """"slax-drake <version>", with " (git <commit>)" when the package runs from a git checkout (" +changes" when
    tracked files differ from the commit). Read once per process."""
    from slax_drake import __version__

    text = f"slax-drake {__version__}"
    here = Path(__file__).resolve().parent
    try:
        commit = subprocess.run(["git", "-C", str(here), "rev-parse", "--short=10", "HEAD"], capture_output=True,
                                text=True, timeout=10, check=True).stdout.strip()
        changed = subprocess.run(["git", "-C", str(here), "status", "--porcelain", "--untracked-files=no"],
                                 capture_output=True, text=True, timeout=10, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return text
    return f"{text} (git {commit}{' +changes' if changed else ''})" if commit else text


def policy_settings(names) -> dict:
    """Per policy name: its registry class and constructor options (what makes it that policy)."""
    from slax_drake.policies.registry import POLICY_TABLE

    return {n: {"class": POLICY_TABLE[n].cls, "options": POLICY_TABLE[n].recorded_options()} for n in names}


def protocol_settings(scenario, config: str, seed: int, perception: str, tool_rules: dict, policies,
                      camera=None, profile: str = "station", oracle_seconds: float | None = None) -> dict:
    """The outcome-changing settings of a Table I run (see the module docstring). ``config`` (the path) is recorded
    for the reader; its content is what is compared. ``camera``: the camera observation mode
    (slax_drake.evaluation.table1.CameraMode) or None (privileged); ``profile``: the action model's rule profile;
    ``oracle_seconds``: the oracles' time limit per decision (None: the Oracle's default)."""
    settings = {
        "observation": "privileged" if camera is None else "camera",
        # full_resolution is recorded only when set, so that the settings of earlier runs still compare equal
        "camera": None if camera is None else {k: v for k, v in dataclasses.asdict(camera).items()
                                               if k != "full_resolution" or v},
        "config": str(config),
        "scenario_sha256": scenario_digest(scenario),
        "seed": int(seed),
        "perception": perception,
        "target_size": [float(v) for v in scenario.target.sizes[0]],
        "horizon_per_object": int(scenario.protocol.horizon_per_object),
        "suction_cost": float(scenario.protocol.suction_cost),
        "visibility_threshold": float(scenario.target.visibility_threshold),
        "profile": profile,
        "tool_rules": dict(tool_rules),
        "oracle_seconds": oracle_seconds,
        "policies": policy_settings(policies),
        "code": [code_version()],
    }
    if tool_rules.get("reach_map"):  # the rule names a file: its content is what decides, not its path
        from slax_drake.shelf.reach import reach_map_file

        settings["reach_map_sha256"] = file_digest(reach_map_file(tool_rules["reach_map"]))
    return settings


# What a mismatch is called in the message, in the order the check reports them (the specific settings before the
# scenario's whole content, so the message names what was changed when it can).
LABELS = {
    "seed": "--seed", "observation": "--observation", "camera": "camera observation (--segmentation, --sensor-noise)",
    "perception": "--perception", "target_size": "target size (scenario target.sizes)",
    "horizon_per_object": "horizon (scenario protocol.horizon_per_object)",
    "suction_cost": "suction cost (scenario protocol.suction_cost)",
    "visibility_threshold": "visibility threshold (scenario target.visibility_threshold)",
    "profile": "--profile (or the scenario's profile)", "oracle_seconds": "--oracle-seconds",
    "drake_observation": "Drake-trial observation (--sensor-noise, or an older version's trial diagram)",
    "tool_rules": "--tool-rule", "reach_map_sha256": "reach map (the reach_map rule's file content)",
    "station_sha256": "station (the --station file's content)", "sleep": "--sleep",
    "scenario_sha256": "scenario (the --config file's content)",
}
INFORMATIONAL = ("config", "station")
# What a record made before a setting existed holds for it (folders made before --observation were privileged).
RECORDED_DEFAULTS = {"observation": "privileged", "camera": None, "profile": "station", "oracle_seconds": None,
                     "reach_map_sha256": None,
                     "drake_observation": "privileged (true poses; before perception was in the loop)"}


def record_or_refuse(out: Path, settings: dict, has_results: bool, name: str = SETTINGS_FILE) -> dict:
    """Checks ``settings`` against ``out``'s record and writes the record (with policies new to the folder added);
    returns the record. ``name``: the record's file name in ``out``; ``has_results``: whether ``out`` already holds result files (a folder with results but
    no record was made before settings were recorded, and is refused: its settings are unknown)."""
    out = Path(out)
    path = out / name
    if path.is_file():
        try:
            recorded = json.loads(path.read_text())
            recorded_policies = dict(recorded["policies"])
        except (OSError, json.JSONDecodeError, KeyError, TypeError) as e:
            raise SettingsMismatchError(f"{path}: unreadable settings record ({e}); use another --out") from None
        for key in [k for k in LABELS if k in settings or k in recorded]:
            if recorded.get(key, RECORDED_DEFAULTS.get(key)) != settings.get(key, RECORDED_DEFAULTS.get(key)):
                raise SettingsMismatchError(
                    f"{out} was made with another {LABELS[key]}: "
                    f"{_show(recorded.get(key, RECORDED_DEFAULTS.get(key)))} there, "
                    f"{_show(settings.get(key))} now; use another --out")
        for name, entry in settings["policies"].items():
            if name in recorded_policies and recorded_policies[name] != entry:
                raise SettingsMismatchError(f"{out} was made with policy {name} built as {recorded_policies[name]}, "
                                            f"not {entry}; use another --out")
        merged = {**settings, "policies": {**recorded_policies, **settings["policies"]}}
        for key in INFORMATIONAL:  # the first run's paths stay on record
            if key in recorded:
                merged[key] = recorded[key]
        codes = list(recorded.get("code", []))  # every code that wrote into the folder, in order
        merged["code"] = codes + [c for c in settings.get("code", []) if c not in codes]
    elif has_results:
        raise SettingsMismatchError(f"{out} holds results but no {name} (made by an older slax-drake): its "
                                    "settings are unknown; use another --out")
    else:
        merged = settings
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(path, json.dumps(merged, indent=1, sort_keys=True))
    return merged


def _show(value) -> str:
    if isinstance(value, str) and len(value) == 64:
        return value[:12]  # a digest
    return json.dumps(value, sort_keys=True)


def physics_run(folder: Path, policy: str) -> tuple[dict, list[Path]]:
    """A physics benchmark's result folder, as the research scripts read it: (its recorded settings, with at least
    ``config`` and ``seed``; the paths of ``policy``'s per-scene trial files, sorted). PhysicsBenchmarkError (one
    line) when the folder holds no readable settings or no trial of ``policy``."""
    folder = Path(folder)
    try:
        settings = json.loads((folder / PHYSICS_SETTINGS_FILE).read_text())
        settings["config"], settings["seed"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise PhysicsBenchmarkError(f"{folder} is no physics benchmark folder with its settings "
                                    f"({type(e).__name__}: {e})") from None
    trials = sorted((folder / "physics_trials" / policy).glob("*.json"))
    if not trials:
        raise PhysicsBenchmarkError(f"no {policy} trials in {folder}/physics_trials")
    return settings, trials
