"""The paper's Table I protocol: every policy on the same seeded scenes of 4, 6, 8 and 10 objects, H = 2n.

Scene seeds: ``scene_seed(protocol_seed, density, index)``, identical for every policy. Each finished trial is
written as its own JSON file under ``<out>/trials/<policy>/<density>_<index>.json`` (atomically), so a run
that is stopped resumes where it was; the settings the trials are made with are recorded in
``<out>/settings.json`` and a run with other settings is refused (:mod:`slax_drake.evaluation.settings`). Trials
run as local processes or Ray tasks (:mod:`slax_drake.backends`); the files are written here, as results come.
When all trials are in, ``table1.json``, ``table1.md`` and ``table1.png`` are (re)written from the trial files of
every policy in the folder, not only those of this run.
"""

from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path

import numpy as np

from slax_drake.config import Scenario
from slax_drake.errors import BenchmarkError
from slax_drake.io import figure_png, json_safe, write_bytes_atomic, write_text_atomic

PAPER_TABLE1 = {  # success % for 4/6/8/10/All (paper Table I)
    "oracle-p": [100, 100, 99, 94, 98], "oracle-p+s": [100, 100, 100, 100, 100], "dar": [77, 68, 45, 24, 54],
    "der-3": [83, 72, 50, 34, 60], "bluction-dar": [96, 92, 88, 67, 86],
}
PAPER_TABLE1_STEPS = {  # median steps (IQR low, high) for 4/6/8/10/All (paper Table I)
    "oracle-p": [(1.5, 1.0, 2.0), (3.0, 2.0, 3.0), (3.0, 2.0, 4.0), (4.0, 3.0, 6.0), (3.0, 2.0, 4.0)],
    "oracle-p+s": [(1.5, 1.0, 2.0), (2.0, 2.0, 3.0), (2.5, 2.0, 3.0), (3.0, 2.0, 4.0), (2.0, 1.0, 3.0)],
    "dar": [(2.0, 1.0, 3.0), (3.0, 1.8, 5.0), (3.0, 1.0, 4.0), (4.5, 2.0, 6.0), (2.0, 1.0, 4.0)],
    "der-3": [(2.0, 1.0, 3.0), (3.0, 1.0, 4.3), (3.0, 2.0, 4.0), (3.0, 2.0, 5.0), (3.0, 1.0, 4.0)],
    "bluction-dar": [(2.0, 1.0, 2.5), (2.0, 2.0, 4.0), (3.0, 2.0, 5.0), (6.0, 3.0, 8.0), (3.0, 2.0, 4.0)],
}


@dataclasses.dataclass(frozen=True)
class CameraMode:
    """``--observation camera``: the non-oracle policies see rendered frames (slax_drake.shelf.simulator.
    CameraObserver): ``segmentation`` "labels" (the render's object labels, idealised) or "depth"
    (segment_depth); ``sensor_noise``: the L515 model, seeded by the scene seed; ``full_resolution``: frames
    ray-cast at the camera's own resolution and resampled to the working one, as the Drake station makes them
    (the physics benchmark's shelf simulator; CameraObserver)."""

    segmentation: str = "labels"
    sensor_noise: bool = False
    full_resolution: bool = False


def trial_oracle_status(searches: list[dict]) -> str:
    """One word for an oracle trial from its searches' statuses: "cut by time" when any search was cut,
    else the first search's ("optimal" or "infeasible"), or "none" when the target was visible from the start."""
    statuses = [s["status"] for s in searches]
    if not statuses:
        return "none"
    if "cut by time" in statuses:
        return "cut by time"
    return statuses[0]


def scene_seed(protocol_seed: int, density: int, index: int) -> int:
    """The scene seed for trial ``index`` of ``density`` objects; the same for every policy."""
    return int(protocol_seed) * 1_000_003 + int(density) * 10_007 + int(index)


def protocol_scene(scenario, density: int, seed: int):
    """The protocol's scene with ``density`` objects for scene seed ``seed`` (see :func:`scene_seed`): the
    protocol's occluder count for that density and its first target size."""
    from slax_drake.scene.sampling import sample_scene

    return sample_scene(scenario, scenario.protocol.occluders(density), seed,
                        target_size=tuple(scenario.target.sizes[0]))


def protocol_frame(scene, width: int = 160, noise_seed: int | None = None):
    """The camera's first frame of ``scene`` at ``width`` px (the height keeps the camera's aspect), the target
    included: ``(camera, depth, labels)`` as the ray caster renders them (depth metres along the optical axis;
    labels 0 shelf, i + 1 for ``scene.objects[i]``, n + 1 the target), the depth with the L515 noise model at step 0
    when ``noise_seed`` is given."""
    from slax_drake.perception.sensor_noise import l515_depth_noise
    from slax_drake.scene.raycast import SceneRaycaster

    camera = scene.camera.with_resolution(width, max(1, round(scene.camera.height * width / scene.camera.width)))
    depth, labels = SceneRaycaster(scene, include_target=True).render(camera)
    if noise_seed is not None:
        depth = l515_depth_noise(depth, camera, noise_seed, 0)
    return camera, depth, labels


def _trial_path(out: Path, policy: str, density: int, index: int) -> Path:
    return out / "trials" / policy / f"{density:02d}_{index:04d}.json"


def run_benchmark_trial(job) -> dict:
    """Runs one trial (in whichever process the backend chose); returns the trial file's content."""
    scenario, policy_name, density, index, seed, perception, tool_rules, camera, profile, oracle_seconds = job
    from slax_drake.policies.registry import is_oracle, make_policy
    from slax_drake.shelf.simulator import CameraObserver, run_trial

    size = tuple(scenario.target.sizes[0])
    scene = protocol_scene(scenario, density, seed)
    horizon = scenario.protocol.horizon_per_object * density
    oracle_options = {"seconds": oracle_seconds} if is_oracle(policy_name) and oracle_seconds else None
    policy = make_policy(policy_name, scenario, perception=perception, horizon=horizon, tool_overrides=tool_rules,
                         profile=profile, oracle_options=oracle_options)
    observer = None
    if camera is not None and not policy.needs_true_scene:  # the oracles always read the true scene
        observer = CameraObserver(scene.shelf, scene.camera, size,
                                  source="network" if perception == "learned" else "depth",
                                  width=policy.observation_width, segmentation=camera.segmentation,
                                  noise_seed=seed if camera.sensor_noise else None,
                                  full_resolution=camera.full_resolution)
    t0 = time.perf_counter()
    result = run_trial(scene, policy, horizon, threshold=scenario.target.visibility_threshold,
                       suction_cost=scenario.protocol.suction_cost, density=density, observer=observer).to_dict()
    result["trial_seconds"] = round(time.perf_counter() - t0, 3)
    result["index"] = index
    result["observation"] = "privileged" if observer is None else "camera"
    result["profile"] = profile
    if tool_rules:
        result["tool_rules"] = tool_rules
    decisions = getattr(policy, "decision_log", None)
    if decisions is not None:  # ours (slax-hindsight, slax-belief): per decision, what the search looked at and chose
        result["decision_log"] = json_safe(decisions)  # numpy scalars
    searches = getattr(policy, "search_log", None)
    if searches is not None:  # the oracles: how each search ended (proven optimal, infeasible, cut by time)
        result["oracle_searches"] = searches
        result["oracle_status"] = trial_oracle_status(searches)
    return result


def run_benchmark(scenario: Scenario, policies, scenes_per_density: int, seed: int, out: Path, workers: int = 1,
                  backend: str = "local", perception: str = "ground-truth", densities=None, progress=True,
                  tool_rules: dict | None = None, config: str | None = None, ray_address: str | None = None,
                  camera: CameraMode | None = None, profile: str | None = None,
                  oracle_seconds: float | None = None) -> dict:
    """Runs the missing trials and writes the tables; returns the table dict (see ``summarise``), whose ``meta``
    says how many trials were kept from the folder and how many ran.

    ``profile``: the action model's rule profile (default: the scenario's); ``tool_rules``: single rule overrides
    on top of it; both recorded in each trial file. ``config``: the scenario's path, recorded beside its content's
    digest. A folder recorded with other settings (profile and rules included) is refused before anything runs
    (:func:`slax_drake.evaluation.settings.record_or_refuse`). ``camera``: the camera observation mode of the
    non-oracle policies (None: privileged, the seen objects with their true shapes and poses; the oracles are
    privileged always).
    ``oracle_seconds``: the oracles' CPU-time limit per decision (default: the Oracle's)."""
    from slax_drake.backends import check_backend, run_tasks
    from slax_drake.evaluation.settings import protocol_settings, record_or_refuse
    from slax_drake.shelf.tool import scenario_profile, without_defaults

    out = Path(out)
    densities = list(densities or scenario.protocol.densities)
    profile = scenario_profile(scenario, profile)
    tool_rules = without_defaults(dict(tool_rules or {}), profile)
    check_backend(backend, workers, ray_address)
    check_protocol_request(scenario, policies, densities)
    settings = protocol_settings(scenario, config or "?", seed, perception, tool_rules, policies, camera, profile,
                                 oracle_seconds)
    record_or_refuse(out, settings, has_results=bool(present_policies(out)))
    jobs, kept = [], 0
    for policy in policies:
        for density in densities:
            for index in range(scenes_per_density):
                if _trial_path(out, policy, density, index).is_file():
                    kept += 1
                else:
                    jobs.append((scenario, policy, density, index, scene_seed(seed, density, index), perception,
                                 tool_rules, camera, profile, oracle_seconds))
    # Heavy policies first, interleaved, so the pool stays busy to the end.
    jobs.sort(key=lambda j: (-j[2], j[3], j[1]))
    start = time.perf_counter()
    if jobs:
        from tqdm import tqdm

        with tqdm(total=len(jobs), desc="trials", disable=not progress, unit="trial") as bar:
            for job, result in run_tasks(run_benchmark_trial, jobs, workers=workers, backend=backend, ray_address=ray_address):
                write_text_atomic(_trial_path(out, job[1], job[2], job[3]), json.dumps(result, sort_keys=True))
                bar.update(1)
    elapsed = time.perf_counter() - start
    in_table = table_policies(out, policies)
    trials, missing = load_trials(out, in_table, densities, scenes_per_density)
    table = summarise(trials, in_table, densities)
    table["meta"] = {"scenes_per_density": scenes_per_density, "seed": seed, "perception": perception,
                     "densities": densities, "wall_seconds_this_run": round(elapsed, 1), "workers": workers,
                     "backend": backend, "profile": profile, "tool_rules": tool_rules, "oracle_seconds": oracle_seconds,
                     "trials_kept": kept, "trials_run": len(jobs),
                     "missing_trials": missing, "observation": "privileged" if camera is None else "camera",
                     "camera": None if camera is None else dataclasses.asdict(camera)}
    write_tables(table, out)
    return table


def present_policies(out: Path) -> list[str]:
    """The policies with at least one trial file in ``out``."""
    root = Path(out) / "trials"
    if not root.is_dir():
        return []
    return sorted(d.name for d in root.iterdir() if d.is_dir() and any(d.glob("*.json")))


def table_policies(out: Path, policies) -> list[str]:
    """The policies of the table: this run's and every other one with trial files in ``out``, in the registry's
    order (then by name)."""
    from slax_drake.policies.registry import POLICY_NAMES

    names = set(policies) | set(present_policies(out))
    order = {n: i for i, n in enumerate(POLICY_NAMES)}
    return sorted(names, key=lambda n: (order.get(n, len(order)), n))


def check_protocol_request(scenario: Scenario, policies, densities) -> None:
    """BenchmarkError for a request that cannot be run as asked, before anything is written: a policy or density
    named twice (each trial would run twice), or a density of more objects than fit in the scenario's bay."""
    from slax_drake.config import max_placeable_objects

    for what, values in (("--policies", list(policies)), ("--densities", [int(n) for n in densities])):
        twice = sorted({str(v) for v in values if values.count(v) > 1})
        if twice:
            raise BenchmarkError(f"{what} names {', '.join(twice)} more than once")
    bound = max_placeable_objects(scenario)
    for n in densities:
        if not 1 <= scenario.protocol.occluders(n) <= bound:
            raise BenchmarkError(f"--densities {n}: a scene of {n} objects cannot be drawn in this bay (at least 1 "
                                 f"and at most {bound} objects of at least {scenario.objects.min_size} m fit on the "
                                 f"{scenario.shelf.width} x {scenario.shelf.depth} m shelf besides the target)")


def check_trial_record(path, record) -> dict:
    """``record`` (the content of a trial file at ``path``) if its fields have the types the table reads, else a
    BenchmarkError naming the first one that does not (a file edited or written by something else)."""
    def fail(field, why):
        raise BenchmarkError(f"{path}: field '{field}' {why}; delete the file to rerun that trial")

    if not isinstance(record, dict):
        raise BenchmarkError(f"{path}: not a trial record (a JSON object); delete the file to rerun that trial")
    for field, kind in (("policy", str), ("success", bool), ("density", int), ("steps", int)):
        if field not in record:
            fail(field, "is missing")
        value = record[field]
        if not isinstance(value, kind) or (kind is int and isinstance(value, bool)):
            fail(field, f"is {value!r}, not {'true or false' if kind is bool else kind.__name__}")
    seconds = record.get("decision_seconds")
    if not (isinstance(seconds, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                              for v in seconds)):
        fail("decision_seconds", "is not a list of numbers")
    return record


def load_trials(out: Path, policies, densities, scenes_per_density) -> tuple[list[dict], dict]:
    """The trial files of scenes 0 .. scenes_per_density - 1 of every density for ``policies``; and per policy the
    number of those that are not in the folder (a policy that an earlier run ran on fewer scenes)."""
    trials, missing = [], {}
    for policy in policies:
        for density in densities:
            for index in range(scenes_per_density):
                path = _trial_path(out, policy, density, index)
                if not path.is_file():
                    missing[policy] = missing.get(policy, 0) + 1
                    continue
                try:
                    record = json.loads(path.read_text())
                except (OSError, json.JSONDecodeError) as e:
                    raise BenchmarkError(f"{path}: unreadable trial file ({e}); delete it to rerun that trial")
                trials.append(check_trial_record(path, record))
    return trials, missing


def summarise(trials: list[dict], policies, densities) -> dict:
    """Per policy and density key ("4", ..., "all"): success_rate, median_steps, iqr, trials (count);
    steps statistics over successful trials, as in the paper's table; plus the raw ``trials`` list."""
    table = {"policies": {}, "trials": [
        {k: t[k] for k in ("seed", "density", "policy", "success", "steps", "cost", "reason", "oracle_status")
         if k in t} for t in trials
    ]}
    for policy in policies:
        per = {}
        for key in [str(d) for d in densities] + ["all"]:
            sel = [t for t in trials if t["policy"] == policy and (key == "all" or t["density"] == int(key))]
            steps = [t["steps"] for t in sel if t["success"]]
            decision = [s for t in sel for s in t["decision_seconds"]]
            per[key] = {
                "success_rate": round(sum(t["success"] for t in sel) / len(sel), 4) if sel else None,
                "median_steps": float(np.median(steps)) if steps else None,
                "iqr": [float(np.percentile(steps, 25)), float(np.percentile(steps, 75))] if steps else None,
                "trials": len(sel),
                "mean_decision_seconds": round(float(np.mean(decision)), 4) if decision else None,
                "mean_trial_seconds": (round(float(np.mean([t["trial_seconds"] for t in sel])), 3)
                                       if sel and all("trial_seconds" in t for t in sel) else None),
            }
            statuses = [t["oracle_status"] for t in sel if "oracle_status" in t]
            if statuses:
                per[key]["oracle_status"] = {s: statuses.count(s) for s in sorted(set(statuses))}
        table["policies"][policy] = per
    return table


def write_tables(table: dict, out: Path) -> None:
    out = Path(out)
    write_text_atomic(out / "table1.json", json.dumps(table, indent=1, sort_keys=True))
    write_text_atomic(out / "table1.md", markdown_table(table))
    write_bytes_atomic(out / "table1.png", bar_chart_png(table))


def markdown_table(table: dict) -> str:
    policies = list(table["policies"])
    keys = [k for k in next(iter(table["policies"].values()))]
    lines = ["| No. | Metric | " + " | ".join(policies) + " |", "|---|---|" + "---|" * len(policies)]
    for key in keys:
        cells_s, cells_m = [], []
        for p in policies:
            e = table["policies"][p][key]
            paper = ""
            if p in PAPER_TABLE1 and key in ("4", "6", "8", "10", "all"):
                paper = f" (paper {PAPER_TABLE1[p][['4', '6', '8', '10', 'all'].index(key)]})"
            cells_s.append("-" if e["success_rate"] is None else f"{100 * e['success_rate']:.0f} %{paper}")
            cells_m.append("-" if e["median_steps"] is None else
                           f"{e['median_steps']:.1f} ({e['iqr'][0]:.1f} - {e['iqr'][1]:.1f})")
        label = "All" if key == "all" else key
        lines.append(f"| {label} | Success rate | " + " | ".join(cells_s) + " |")
        lines.append(f"| {label} | Median steps (IQR) | " + " | ".join(cells_m) + " |")
    lines.append("| All | Mean decision time per step (s) | " + " | ".join(
        "-" if table["policies"][p]["all"]["mean_decision_seconds"] is None
        else f"{table['policies'][p]['all']['mean_decision_seconds']:.3f}" for p in policies) + " |")
    meta = table.get("meta", {})
    lines.append("")
    lines.append(f"{meta.get('scenes_per_density', '?')} scenes per density, protocol seed {meta.get('seed', '?')}, "
                 f"{meta.get('perception', '?')} distributions; steps over successful trials."
                 + f" Action-model rules: the '{meta.get('profile', 'station')}' profile"
                 + (f", with {', '.join(f'{k} = {v}' for k, v in meta['tool_rules'].items())}."
                    if meta.get("tool_rules") else "."))
    if meta.get("observation") == "camera":
        cam = meta.get("camera") or {}
        lines.append(f"Observation: camera (rendered frames, {cam.get('segmentation', '?')} segmentation"
                     f"{', L515 sensor noise' if cam.get('sensor_noise') else ''}, estimator hypotheses, distributions "
                     "from the frame and its predicted successors) for every policy but the oracles, which read the "
                     "true scene (privileged) in every mode.")
    else:
        lines.append("Observation: privileged (the objects seen with their true shapes and poses; P_t of the true "
                     "scene).")
    for policy, count in (meta.get("missing_trials") or {}).items():
        lines.append(f"{policy}: {count} of these trials are not in the folder (run it with --policies {policy} to "
                     "complete them); its figures are over the trials present.")
    status = {p: table["policies"][p]["all"].get("oracle_status") for p in policies}
    if any(status.values()):
        lines.append("")
        lines.append("Oracle searches per trial (proven optimal / proven infeasible within H / cut by time): "
                     + "; ".join(f"{p}: " + ", ".join(f"{k} {v}" for k, v in s.items())
                                 for p, s in status.items() if s) + ".")
    return "\n".join(lines) + "\n"


def bar_chart_png(table: dict) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    policies = list(table["policies"])
    keys = list(next(iter(table["policies"].values())))
    fig, ax = plt.subplots(figsize=(8, 4))
    width = 0.8 / max(1, len(policies))
    for i, p in enumerate(policies):
        rates = [100 * (table["policies"][p][k]["success_rate"] or 0) for k in keys]
        ax.bar(np.arange(len(keys)) + i * width, rates, width, label=p)
    ax.set_xticks(np.arange(len(keys)) + width * (len(policies) - 1) / 2)
    ax.set_xticklabels(["All" if k == "all" else f"{k} objects" for k in keys])
    ax.set_ylabel("success rate (%)")
    ax.set_ylim(0, 105)
    ax.legend(fontsize=8, ncol=3)
    ax.set_title("Table I protocol (fast first-order shelf simulator)")
    fig.tight_layout()
    return figure_png(fig, 120)
