"""A physics benchmark's scene as a ``slax-drake trial``: ``--benchmark-scene N:INDEX``
(:func:`benchmark_scene_options`: the protocol's scene, with the command line's options) and ``--from-benchmark
FOLDER`` (the trial a finished run ran for it, with that run's recorded options).

A physics benchmark's folder records what its Drake trials ran with (``physics_settings.json``: the scenario, the
station and its digest, the rule profile and the rules in force, the policies, the sensor-noise model, object
sleep). :func:`benchmark_trial_options` turns it and a scene ``N:INDEX`` into the options of that very trial, so
that a person can watch a benchmark trial in Meshcat or read its step figures without copying the run's rules by
hand; :func:`benchmark_record` finds that run's own record of the scene (its trial file, or the summary entry a
``docs/results`` copy keeps) and :func:`agreement` says in one line whether the trial just run did the same.

Same code, same files, same machine: the same trial (a Drake trial is deterministic). The notes
:func:`benchmark_trial_options` returns say where that cannot hold: a station or scenario file whose content
differs from the run's, or a run made by another commit.
"""

from __future__ import annotations

import json
from pathlib import Path

from slax_drake.errors import TrialError

SETTINGS_KEYS = ("config", "seed", "policies", "profile", "tool_rules", "station_sha256", "scenario_sha256",
                 "drake_observation", "sleep")


def benchmark_scene_options(opts, spec: str, protocol_seed: int | None = None):
    """``opts`` (TrialOptions) set to the protocol scene ``spec`` = "N:INDEX" of ``opts.config``: N objects, the
    scene seed ``scene_seed(protocol seed, N, INDEX)`` (``protocol_seed``, default the scenario's: a benchmark's
    ``--seed``), the protocol's first target size, H = horizon_per_object * N and, unless a station is given, the
    physics benchmark's default station: the very trial the physics benchmark runs."""
    from slax_drake.config import load_scenario
    from slax_drake.evaluation.table1 import scene_seed
    from slax_drake.evaluation.physics import protocol_trial

    try:
        density, index = (int(v) for v in spec.split(":"))
    except ValueError:
        raise TrialError(f"--benchmark-scene takes N:INDEX, e.g. 8:1 (got {spec!r})") from None
    if density < 1 or index < 0:
        raise TrialError(f"--benchmark-scene needs N >= 1 objects and INDEX >= 0 (got {spec!r})")
    scenario = load_scenario(opts.config)
    seed = scenario.protocol.seed if protocol_seed is None else int(protocol_seed)
    return protocol_trial(opts, scenario, density, scene_seed(seed, density, index))


def read_benchmark_settings(folder: str | Path) -> dict:
    """The physics benchmark settings of ``folder`` (its physics_settings.json); TrialError (exit 2) when the
    folder or the file is missing, the file is not JSON, or it lacks a field the trial needs."""
    from slax_drake.evaluation.settings import PHYSICS_SETTINGS_FILE

    path = Path(folder) / PHYSICS_SETTINGS_FILE
    if not Path(folder).is_dir():
        raise TrialError(f"--from-benchmark: no folder {folder}")
    try:
        settings = json.loads(path.read_text())
    except FileNotFoundError:
        raise TrialError(f"--from-benchmark: {folder} holds no {PHYSICS_SETTINGS_FILE}: not a physics benchmark's "
                         f"folder (slax-drake benchmark --physics --out FOLDER)") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise TrialError(f"--from-benchmark: {path} is not a settings file ({e})") from None
    missing = [k for k in SETTINGS_KEYS if not isinstance(settings, dict) or k not in settings]
    if missing:
        raise TrialError(f"--from-benchmark: {path} lacks {', '.join(missing)}: not a physics benchmark's settings, "
                         f"or one from before they were recorded")
    return settings


def benchmark_trial_options(folder: str | Path, spec: str, policy: str | None = None, station: str | None = None,
                            extra_rules: list[str] | None = None, **trial_fields) -> tuple:
    """(TrialOptions, notes): the trial the physics benchmark in ``folder`` ran for its scene ``spec`` ("N:INDEX"),
    with the run's scenario and protocol seed, rule profile, rules (``extra_rules``, ``--tool-rule`` items, on
    top), sensor-noise model and object sleep, and ``policy`` (default: the run's one policy; required when it ran
    several).
    ``station`` (default: the benchmark's default station for the scenario, the run's own path may be gone) is
    checked against the run's digest. ``notes``: one line per reason the trial may differ from the run's.
    ``trial_fields``: further TrialOptions fields (meshcat, html, out, max_sim_time)."""
    from slax_drake.config import load_scenario
    from slax_drake.evaluation.physics import drake_observation
    from slax_drake.evaluation.settings import code_version, file_digest, scenario_digest
    from slax_drake.shelf.tool import parse_tool_rules
    from slax_drake.station.scenario import station_for
    from slax_drake.systems.trial import TrialOptions

    settings = read_benchmark_settings(folder)
    ran = list(settings["policies"])
    if policy is None:
        if len(ran) != 1:
            raise TrialError(f"--from-benchmark: the run in {folder} ran {', '.join(ran)}: name one with --policy")
        policy = ran[0]
    elif policy not in ran:
        raise TrialError(f"--from-benchmark: the run in {folder} ran {', '.join(ran)}, not {policy}")
    config = str(settings["config"])
    if not Path(config).is_file():
        raise TrialError(f"--from-benchmark: the run's scenario {config} is not here (run from the repository root)")
    profile = str(settings["profile"])
    recorded = settings["tool_rules"] or {}
    if not isinstance(recorded, dict):
        raise TrialError(f"--from-benchmark: the run's tool_rules is not a table of rules ({recorded!r})")
    rules = parse_tool_rules([f"{k}={v}" for k, v in recorded.items()] + list(extra_rules or ()), profile)
    noise = {drake_observation(False): False, drake_observation(True): True}.get(settings["drake_observation"])
    if noise is None:
        raise TrialError(f"--from-benchmark: the run's Drake observation is not one this code makes "
                         f"({settings['drake_observation']!r})")
    opts = TrialOptions(config=config, policy=policy, station=station or station_for(config), profile=profile,
                        tool_rules=rules, sensor_noise=noise, sleep=bool(settings["sleep"]), **trial_fields)
    if not isinstance(settings["seed"], int):
        raise TrialError(f"--from-benchmark: the run's protocol seed is not an integer ({settings['seed']!r})")
    opts = benchmark_scene_options(opts, spec, protocol_seed=settings["seed"])
    notes = []
    if not Path(opts.station).is_file():
        raise TrialError(f"--from-benchmark: station file not found: {opts.station}")
    if file_digest(opts.station) != settings["station_sha256"]:
        notes.append(f"the station file {opts.station} differs from the one the run used")
    if scenario_digest(load_scenario(config)) != settings["scenario_sha256"]:
        notes.append(f"the scenario {config} differs from the one the run used")
    if extra_rules:
        notes.append(f"--tool-rule {' '.join(extra_rules)} on top of the run's rules")
    code = (settings.get("code") or [None])[-1]
    if code and code != code_version():
        notes.append(f"the run was made by {code}, this is {code_version()}")
    return opts, notes


def benchmark_record(folder: str | Path, policy: str, density: int, index: int) -> dict | None:
    """The run's own record of the scene: ``{"result", "actions"}`` from its trial file
    (``physics_trials/POLICY/NN_IIII.json``, the actions as (type, object, d, dx, dz)), else ``{"result",
    "actions_executed"}`` from physics.json's summary entry (what a ``docs/results`` copy keeps); None when the
    folder holds neither (a run stopped before the scene)."""
    from slax_drake.evaluation.physics import trial_path

    path = trial_path(Path(folder), policy, density, index)
    try:
        drake = json.loads(path.read_text())["drake"]
        return {"result": drake["result"], "actions": [action_key(a) for a in drake["actions"]]}
    except (FileNotFoundError, json.JSONDecodeError, KeyError, TypeError):
        pass
    try:
        trials = json.loads((Path(folder) / "physics.json").read_text())["trials"]
    except (FileNotFoundError, json.JSONDecodeError, KeyError, TypeError):
        return None
    for t in trials:
        if (t.get("policy"), t.get("density"), t.get("index")) == (policy, density, index) and "drake_result" in t:
            # a summary from before "actions_executed" was kept counts them as the trial's steps
            return {"result": t["drake_result"], "actions_executed": t.get("actions_executed", t.get("drake_steps"))}
    return None


def action_key(action: dict) -> tuple:
    """An executed action as the benchmark and the trial both record it: (type, object, d, dx, dz)."""
    return (action["type"], action["object"], action.get("d"), action.get("dx"), action.get("dz"))


def agreement(data: dict, run: dict | None, folder) -> str:
    """One line: whether the trial record ``data`` did what the run's record ``run`` (:func:`benchmark_record`)
    says that run did."""
    if run is None:
        return f"the run in {folder} holds no record of this scene"
    mine = [action_key(a) for a in data["actions"]]
    ended = f"ended \"{run['result']}\""
    if "actions" in run:
        theirs = run["actions"]
        first = next((k for k, (a, b) in enumerate(zip(mine, theirs)) if a != b), min(len(mine), len(theirs)))
        if mine == theirs and data["result"] == run["result"]:
            return f"as the run in {folder}: the same {len(mine)} actions, {ended}"
        return (f"NOT as the run in {folder} ({ended} after {len(theirs)} actions): the actions part at action "
                f"{first + 1}" + (f', this trial ended "{data["result"]}"' if data["result"] != run["result"] else ""))
    same = len(mine) == run["actions_executed"] and data["result"] == run["result"]
    return (f"{'as' if same else 'NOT as'} the run in {folder} ({ended} after {run['actions_executed']} actions; its "
            f"summary keeps no actions to compare one by one)")
