"""Results pages from benchmark result folders: ``slax-drake report RESULTS... --docs docs/ [--readme README.md]``.

Every results table of the documentation is generated here from the files ``slax-drake benchmark`` writes, never
typed by hand. What a folder feeds is read from its files:

- ``table1.json`` (``slax-drake benchmark``): a section of the Table I page (the paper's layout: success rate and
  median steps per density, the paper's figure in parentheses, the median action cost and the decision time);
  a privileged folder and a camera folder of the same protocol (seed, scenes per density, profile, distribution
  model) also give a row per shared non-oracle policy of the observation-modes comparison.
- ``physics.json`` (``slax-drake benchmark --physics``): a section of the physics-benchmark page (success in the
  shelf simulator and in Drake, the actions whose physical outcome matched the action model's prediction, Drake's
  trial endings); a run of the Table II protocol (scenario ``table2.yaml``) also gives the Table II page, beside
  the paper's real-Fetch figures.

Each table names the command, the rule profile and the observation mode it was made with, and every page the
exact ``slax-drake report`` command that regenerates it. With ``readme`` the headline table (the first Table I
folder's success rates, with the rows of any later folder given that reran some of its policies on the same
protocol) replaces the text between the README's ``<!-- results:begin -->`` and
``<!-- results:end -->`` markers, and the first physics folder's section (not a Table II run) the text between
``<!-- physics:begin -->`` and ``<!-- physics:end -->``.
"""

from __future__ import annotations

import json
import shlex
import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from slax_drake.errors import UserError
from slax_drake.io import file_in_the_way, write_text_atomic

KEYS = ("4", "6", "8", "10", "all")
README_BEGIN, README_END = "<!-- results:begin -->", "<!-- results:end -->"
PHYSICS_BEGIN, PHYSICS_END = "<!-- physics:begin -->", "<!-- physics:end -->"  # the README's Drake headline
NAMES = {"oracle-p": "Oracle-P", "oracle-p+s": "Oracle-P+S", "dar": "DAR", "der-3": "DER-3",
         "bluction-dar": "Bluction-DAR", "dar-literal": "DAR, literal", "bluction-dar-literal": "Bluction-DAR, literal"}
# Paper Table II (Sec. VI-B): successes of 3 physical shelves per density with the real Fetch.
PAPER_TABLE2 = {"der-3": {"8": (0, 3), "10": (2, 3), "12": (1, 3)},
                "bluction-dar": {"8": (3, 3), "10": (3, 3), "12": (3, 3)}}
PAGES = {"table1": "table-i.md", "modes": "observation-modes.md", "physics": "physics-benchmark.md",
         "table2": "table-ii.md"}
TITLES = {"table1": "Table I in the shelf simulator", "modes": "Camera against privileged observation",
          "physics": "The physics benchmark (Drake beside the shelf simulator)",
          "table2": "Table II protocol in Drake"}


@dataclass(frozen=True, eq=False)
class ResultFolder:
    """One result folder as given on the command line: ``kind`` is ``table1`` or ``physics``; ``summary`` the
    folder's table1.json or physics.json; ``settings`` its settings.json or physics_settings.json ({} if none)."""

    path: Path
    kind: str
    summary: dict
    settings: dict

    @property
    def meta(self) -> dict:
        return self.summary.get("meta", {})

    @property
    def config(self) -> str:
        return self.settings.get("config") or self.meta.get("config") or "sim_configs/table1.yaml"

    @property
    def profile(self) -> str:
        return self.meta.get("profile") or self.settings.get("profile") or "station"

    @property
    def is_table2(self) -> bool:
        return self.kind == "physics" and Path(self.config).stem == "table2"


def _load_json(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as e:
        raise UserError(f"{path}: not a JSON file ({e.msg} at line {e.lineno})") from None


def load_folder(path: Path) -> ResultFolder:
    """Reads a result folder; a folder with neither table1.json nor physics.json is refused (UserError)."""
    path = Path(path)
    if not path.is_dir():
        raise UserError(f"{path}: no such result folder")
    for kind, summary, settings in (("table1", "table1.json", "settings.json"),
                                    ("physics", "physics.json", "physics_settings.json")):
        if (path / summary).is_file():
            settings_path = path / settings
            return ResultFolder(path, kind, _load_json(path / summary),
                                _load_json(settings_path) if settings_path.is_file() else {})
    raise UserError(f"{path} holds neither table1.json nor physics.json (folders written by slax-drake benchmark)")


def _policy_order(names) -> list[str]:
    from slax_drake.policies.registry import POLICY_NAMES

    order = {n: i for i, n in enumerate(POLICY_NAMES)}
    return sorted(names, key=lambda n: (order.get(n, len(order)), n))


def _display(policy: str) -> str:
    from slax_drake.policies.registry import is_ours

    return NAMES.get(policy, policy + (" (ours)" if is_ours(policy) else ""))


def _pct(rate) -> str:
    return "-" if rate is None else f"{100 * rate:.0f} %"


def _count(n) -> str:
    return "-" if n is None else str(n)


# the rules a physics run takes from its station file (``systems.trial.station_tool_rules``), not the command line
STATION_RULES = frozenset({"max_suction_moment", "max_drag_pull", "max_drag_twist", "max_seal_angle_deg", "reach_map"})


def _physics_rule_args(rules: dict) -> dict:
    """The --tool-rule values a physics run with these recorded rules needs now: the station files give their cup's
    limits, reach map, guarded placement (``guarded_placement``: suction_hidden_rule=guarded) and push model
    (``push_turn``: quasi-static), so a run recorded without one of those two rules (before the stations set it, or
    with it taken away) needs suction_hidden_rule=placement or push_turn=none."""
    args = {k: v for k, v in rules.items() if k not in STATION_RULES}
    for rule, station_value, without in (("suction_hidden_rule", "guarded", "placement"),
                                         ("push_turn", "quasi-static", "none")):
        if args.get(rule) == station_value:
            del args[rule]
        elif rule not in args:
            args[rule] = without
    return args


def _tool_rule_args(rules: dict) -> str:
    return "".join(f" --tool-rule {k}={v}" for k, v in sorted((rules or {}).items()))


def benchmark_command(folder: ResultFolder) -> str:
    """The ``slax-drake benchmark`` command line that makes (or resumes) the folder's run, from its settings."""
    meta, settings = folder.meta, folder.settings
    policies = ",".join(_policy_order(folder.summary.get("policies", {})))
    densities = meta.get("densities")
    parts = ["slax-drake benchmark"]
    if folder.kind == "physics":
        parts.append("--physics")
    parts.append(f"--config {folder.config}")
    if folder.kind == "table1":
        parts.append(f"--profile {folder.profile}")
        parts.append(f"--observation {meta.get('observation') or settings.get('observation') or 'privileged'}")
        camera = settings.get("camera") or {}
        if camera.get("segmentation", "labels") != "labels":
            parts.append(f"--segmentation {camera['segmentation']}")
        if camera.get("sensor_noise"):
            parts.append("--sensor-noise")
        if camera.get("full_resolution"):
            parts.append("--full-resolution")
        perception = meta.get("perception") or settings.get("perception") or "ground-truth"
        if perception != "ground-truth":
            parts.append(f"--perception {perception}")
        if meta.get("oracle_seconds"):
            parts.append(f"--oracle-seconds {meta['oracle_seconds']:g}")
        parts.append(_tool_rule_args(meta.get("tool_rules")).strip())
    parts.append(f"--policies {policies}")
    parts.append(f"--scenes-per-density {meta.get('scenes_per_density', '?')} --seed {meta.get('seed', 0)}")
    if densities and folder.kind == "table1" and sorted(densities) != [4, 6, 8, 10]:
        parts.append("--densities " + ",".join(str(d) for d in densities))
    parts.append(f"--workers {meta.get('workers', 2)}")
    if folder.kind == "physics":
        # the station file gives its cup's limits and reach map; any other rule came from the command line
        parts.append(_tool_rule_args(_physics_rule_args(meta.get("tool_rules") or {})).strip())
        if meta.get("shelf_observation") == "camera":
            parts.append("--observation camera")
        if meta.get("sensor_noise"):
            parts.append("--sensor-noise")
        if meta.get("sleep"):
            parts.append("--sleep")
    parts.append(f"--out {folder.path}")
    return " ".join(p for p in parts if p)


def _median_cost(trials: list[dict], policy: str) -> float | None:
    costs = [t["cost"] for t in trials if t["policy"] == policy and t["success"]]
    return float(np.median(costs)) if costs else None


def _observation_words(folder: ResultFolder) -> str:
    meta = folder.meta
    observation = meta.get("observation") or folder.settings.get("observation") or "privileged"
    camera = folder.settings.get("camera") or {}
    if observation == "camera":
        segmentation = camera.get("segmentation", "labels")
        observation += (" (depth-only segmentation" if segmentation == "depth" else " (the render's labels")
        observation += ", L515 depth noise" if camera.get("sensor_noise") else ""
        observation += (", frames rendered at the camera's resolution and resampled as the station's)"
                        if camera.get("full_resolution") else ")")
    return f"{observation} observation, {meta.get('perception') or 'ground-truth'} distributions"


def _density_keys(per: dict) -> list[str]:
    """The density keys of a per-policy summary that hold trials, in object count order, "all" last."""
    return sorted((k for k in per if per.get(k)), key=lambda k: (k == "all", int(k) if k.isdigit() else 0))


def table1_section(folder: ResultFolder) -> str:
    """Markdown of one Table I folder: a heading naming profile and observation mode, the command, the table."""
    from slax_drake.evaluation.table1 import PAPER_TABLE1, PAPER_TABLE1_STEPS

    table, meta = folder.summary, folder.meta
    policies = _policy_order(table["policies"])
    lines = [f"### `{folder.path.name}`: profile `{folder.profile}`, {_observation_words(folder)}", "",
             f"{meta.get('scenes_per_density', '?')} scenes per density, protocol seed {meta.get('seed', '?')}. "
             f"Made with:", "", "```bash", benchmark_command(folder), "```", "",
             "| No. | Metric | " + " | ".join(_display(p) for p in policies) + " |",
             "|---|---|" + "---|" * len(policies)]
    for i, key in enumerate(KEYS):
        rates, steps = [], []
        for p in policies:
            e = table["policies"][p].get(key) or {}
            paper = f" ({PAPER_TABLE1[p][i]})" if p in PAPER_TABLE1 else ""
            rates.append("-" if e.get("success_rate") is None else f"{100 * e['success_rate']:.0f} %{paper}")
            ps = PAPER_TABLE1_STEPS.get(p)
            paper_s = f" ({ps[i][0]:g}, {ps[i][1]:g}-{ps[i][2]:g})" if ps else ""
            steps.append("-" if e.get("median_steps") is None else
                         f"{e['median_steps']:g} ({e['iqr'][0]:g}-{e['iqr'][1]:g}){paper_s}")
        label = "All" if key == "all" else key
        lines.append(f"| {label} | Success rate | " + " | ".join(rates) + " |")
        lines.append(f"| {label} | Median steps (IQR) | " + " | ".join(steps) + " |")
    costs = [_median_cost(table.get("trials", []), p) for p in policies]
    lines.append("| All | Median action cost | " + " | ".join("-" if c is None else f"{c:.1f}" for c in costs) + " |")
    seconds = [table["policies"][p]["all"].get("mean_decision_seconds") for p in policies]
    lines.append("| All | Mean decision time per step (s) | "
                 + " | ".join("-" if s is None else f"{s:.3f}" for s in seconds) + " |")
    statuses = {p: table["policies"][p]["all"].get("oracle_status") for p in policies}
    if any(statuses.values()):
        lines += ["", "Oracle searches per trial (proven optimal / proven infeasible within H / cut by time): "
                  + "; ".join(f"{_display(p)}: " + ", ".join(f"{k} {v}" for k, v in s.items())
                              for p, s in statuses.items() if s) + "."]
    return "\n".join(lines) + "\n"


def _protocol(folder: ResultFolder) -> tuple:
    meta = folder.meta
    return (meta.get("seed"), meta.get("scenes_per_density"), folder.profile, meta.get("perception") or "ground-truth")


def _policy_record(folder: ResultFolder, policy: str) -> dict | None:
    """The policy's class and options as the folder's settings record them (None: not recorded)."""
    return (folder.settings.get("policies") or {}).get(policy)


def observation_mode_rows(folders: list[ResultFolder]) -> list[tuple[ResultFolder, ResultFolder, str]]:
    """(privileged folder, camera folder, policy) for every non-oracle policy of every camera folder, paired with
    a privileged folder of the same protocol that holds the policy with the same recorded class and options: one
    with the camera folder's very policy set if given (its counterpart run), else the first given."""
    from slax_drake.policies.registry import is_oracle

    table1 = [f for f in folders if f.kind == "table1"]
    privileged = [f for f in table1 if (f.meta.get("observation") or "privileged") == "privileged"]
    rows, seen = [], set()
    for cam in (f for f in table1 if f.meta.get("observation") == "camera"):
        for policy in _policy_order(cam.summary["policies"]):
            if is_oracle(policy) or (policy, _protocol(cam)) in seen:
                continue
            # The privileged run of the same policy set (the camera run's counterpart) first, then the first
            # privileged folder given that holds the policy.
            candidates = [f for f in privileged if _protocol(f) == _protocol(cam) and policy in f.summary["policies"]
                          and _policy_record(f, policy) in (None, _policy_record(cam, policy))]
            candidates.sort(key=lambda f: set(f.summary["policies"]) != set(cam.summary["policies"]))
            match = candidates[0] if candidates else None
            if match is not None:
                seen.add((policy, _protocol(cam)))
                rows.append((match, cam, policy))
    return rows


def observation_modes_section(folders: list[ResultFolder]) -> str:
    """Markdown of the camera-against-privileged comparison, one table per profile and protocol."""
    rows = observation_mode_rows(folders)
    if not rows:
        return ""
    groups: dict[tuple, list] = {}
    for priv, cam, policy in rows:
        seed, spd, profile, _ = _protocol(cam)
        groups.setdefault((profile, spd, seed), []).append((priv, cam, policy))
    out = []
    for (profile, spd, seed), group in groups.items():
        lines = [f"### Profile `{profile}`, {spd} scenes per density, protocol seed {seed}", "",
                 "Success % privileged / camera (difference in points); the oracles read the true scene in both "
                 "modes and are left out. Each row's two folders:", ""]
        pairs = list(dict.fromkeys((priv.path, cam.path) for priv, cam, _ in group))
        lines += [f"- `{p}` (privileged) and `{c}` (camera)" for p, c in pairs]
        lines += ["", "| policy | distributions | " + " | ".join("All" if k == "all" else f"{k} objects" for k in KEYS)
                  + " | decision time per step, privileged / camera (s) |", "|---" * (len(KEYS) + 3) + "|"]
        group = sorted(group, key=lambda r: (r[1].meta.get("perception") != "ground-truth", r[2]))
        for priv, cam, p in group:
            cells = []
            for k in KEYS:
                a = (priv.summary["policies"][p].get(k) or {}).get("success_rate")
                b = (cam.summary["policies"][p].get(k) or {}).get("success_rate")
                cells.append("-" if a is None or b is None else f"{100 * a:.0f} / {100 * b:.0f} ({100 * (b - a):+.0f})")
            t = [f.summary["policies"][p]["all"].get("mean_decision_seconds") for f in (priv, cam)]
            times = " / ".join("-" if s is None else f"{s:.3f}" for s in t)
            lines.append(f"| {p} | {cam.meta.get('perception') or 'ground-truth'} | " + " | ".join(cells)
                         + f" | {times} |")
        out.append("\n".join(lines) + "\n")
    return "\n".join(out)


def _drake_mode(folder: ResultFolder) -> tuple[str, str]:
    """(heading words, sentence) for what a physics folder's Drake trials saw, as its settings record it."""
    from slax_drake.evaluation.physics import drake_observation

    meta = folder.meta
    if folder.settings.get("drake_observation"):
        return ("Drake trials in camera mode" + (" with sensor noise" if meta.get("sensor_noise") else ""),
                f"Drake trials in {drake_observation(bool(meta.get('sensor_noise')))}")
    return ("Drake trials' observation not recorded",
            "The folder's settings do not record what the Drake trials saw (a run from before that was recorded)")


def physics_section(folder: ResultFolder) -> str:
    """Markdown of one physics-benchmark folder: profile, the two simulators' observation modes, the command and
    per policy and density the success in both simulators, the matched actions and Drake's endings."""
    from slax_drake.evaluation.physics import planning_cell, stall_words
    from slax_drake.scene.mass import mass_model_words

    meta = folder.meta
    rules = ", ".join(f"{k} = {v}" for k, v in (meta.get("tool_rules") or {}).items())
    mode, seen = _drake_mode(folder)
    lines = [f"### `{folder.path.name}`: profile `{folder.profile}`, {mode}", "",
             f"{seen}; the shelf simulator beside them "
             + (("in camera mode (the same labels and noise model"
                 + ("; its frames rendered at the camera's resolution and resampled as the station's"
                    if meta.get("shelf_full_resolution") else "") + ")")
                if meta.get("shelf_observation") == "camera" else "privileged") + ". "
             f"Object masses: {mass_model_words(meta.get('mass_model'))}. "
             + (f"Rules beyond the profile: {rules}. " if rules else "") + "Made with:", "",
             "```bash", benchmark_command(folder), "```", "",
             "| policy | objects | scenes | shelf simulator | Drake | Drake, nothing lost | actions matching the "
             "prediction | Drake endings | trials with a reversal / an undo | planning per action, median / p90 (s): wall; "
             "CPU |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for policy, per in folder.summary["policies"].items():
        for key in _density_keys(per):
            e = per[key]
            endings = ", ".join(f"{k} {v}" for k, v in sorted((e.get("drake_endings") or {}).items()))
            lines.append(f"| {policy} | {'All' if key == 'all' else key} | {e['trials']} | "
                         f"{_pct(e['shelf_success_rate'])} | {_pct(e['drake_success_rate'])} | "
                         f"{_pct(e.get('drake_clean_success_rate'))} | {_pct(e['match_rate'])} "
                         f"({e['actions_matched']}/{e['actions_judged']}) | {endings} | "
                         f"{_count(e.get('trials_with_reversal'))} / {_count(e.get('trials_with_undo'))} | "
                         f"{planning_cell(e)} |")
    for policy, per in folder.summary["policies"].items():
        rules = per.get("all", {}).get("undo_rules")
        if rules and set(rules) != {"not recorded"}:
            lines += ["", f"{policy}, the undos by how its no-shuttle correction judged them (the action's "
                      "`reversal_rule`): " + ", ".join(f"{k} {v}" for k, v in rules.items()) + "."]
            e = per["all"]
            if "undoes_commanded" in e:
                commanded = e["commanded_undo_rules"]
                lines[-1] += (f" Along an axis the action commands (a push moves its object along x, a suction along "
                              f"x by dx and y by dz; the rest is drift): {_count(e['undoes_commanded'])} in "
                              f"{_count(e['trials_with_commanded_undo'])} trials"
                              + (" (" + ", ".join(f"{k} {v}" for k, v in commanded.items()) + ")" if commanded else "")
                              + ".")
            if e.get("undoes_by_axis") is not None:
                lines[-1] += (f" Against the object's last move along that axis (a move along the other axis alone in "
                              f"between does not hide a cycle): {_count(e['undoes_by_axis'])} in "
                              f"{_count(e['trials_with_axis_undo'])} trials.")
        stalls = per.get("all", {}).get("stalls")
        if stalls:
            lines += ["", f"{policy}, its stalls (the first decision at which no plan of the policy's reveals "
                      f"anything; research/stall_analysis.py): {stall_words(stalls)}"]
    lines += ["", "Reversal: an executed move of an object back along x or y against its previous move (both over "
              "1 cm, judged from the true poses): the shuttles the no-shuttle rule forbids and the reversals it lets "
              "through because they uncover space no earlier arrangement uncovered; most carry the object past where it "
              "stood. Undo: a reversal that ends no farther from where the object stood before its previous move "
              "than that move took it (put back, or past by no more: the shuttle the no-shuttle rule is meant to stop) "
              "(\"-\": a run from before it was counted). Planning per executed action: every candidate motion "
              "planned for that decision, the rejected ones included; wall clock, and the planning process's CPU time (what "
              "one core spends; it grows too when more processes than cores share the machine: the same 80 scenes "
              "read 0.60 / 2.41 s beside another physics run and 0.23 / 0.97 s alone; a run from before it was "
              "recorded shows the wall clock only)."]
    # prose wrapped (a paragraph in Markdown), tables and commands as they are
    lines = [textwrap.fill(l, 116, break_long_words=False, break_on_hyphens=False)
             if len(l) > 116 and not l.startswith(("|", "slax-drake", "`")) else l for l in lines]
    return "\n".join(lines) + "\n"


def table2_section(folder: ResultFolder) -> str:
    """Markdown of a Table II physics run beside the paper's real-Fetch successes (3 shelves per density)."""
    per_policy = folder.summary["policies"]
    mode, seen = _drake_mode(folder)
    lines = [f"### `{folder.path.name}`: profile `{folder.profile}`, {mode}", "", f"{seen}. "
             "The paper's column: 3 physical shelves per density with the real Fetch (Sec. VI-B, Table II). Made "
             "with:", "", "```bash", benchmark_command(folder), "```", "",
             "| objects | policy | paper (real Fetch) | Drake: success | Drake: nothing lost | shelf simulator, same "
             "scenes | Drake endings |", "|---|---|---|---|---|---|---|"]

    def count(e, rate):
        return "-" if e.get(rate) is None else f"{round(e[rate] * e['trials'])}/{e['trials']}"

    for policy in _policy_order(per_policy):
        paper = PAPER_TABLE2.get(policy, {})
        for key in _density_keys(per_policy[policy]):
            e = per_policy[policy][key]
            if key == "all":
                won = sum(w for w, _ in paper.values())
                of = sum(n for _, n in paper.values())
            else:
                won, of = paper.get(key, (None, None))
            endings = ", ".join(f"{k} {v}" for k, v in sorted((e.get("drake_endings") or {}).items()))
            lines.append(f"| {'all' if key == 'all' else key} | {policy} | {'-' if not of else f'{won}/{of}'} | "
                         f"{count(e, 'drake_success_rate')} | {count(e, 'drake_clean_success_rate')} | "
                         f"{count(e, 'shelf_success_rate')} | {endings} |")
    return "\n".join(lines) + "\n"


def is_rerun_of(later: ResultFolder, first: ResultFolder) -> bool:
    """Whether ``later`` is a Table I run of ``first``'s very protocol (its settings but the policy set, and its
    scenes per density and densities) that reran some of its policies: its rows replace ``first``'s in the
    headline. The code that made each (the settings' ``code``) is no part of the protocol: a rerun is made later."""
    def protocol(f):
        return ({k: v for k, v in f.settings.items() if k not in ("policies", "code")},
                f.meta.get("scenes_per_density"), sorted(f.meta.get("densities") or []))

    shared = set(later.summary["policies"]) & set(first.summary["policies"])
    return (later is not first and later.kind == first.kind == "table1" and bool(first.settings)
            and protocol(later) == protocol(first) and bool(shared))


def headline_table(folder: ResultFolder, reruns: list[ResultFolder] = ()) -> str:
    """The README's headline: success % per density of every policy of a Table I folder, the paper's figure in
    parentheses, naming the command, the profile and the observation mode. A policy that a later run of the same
    protocol (``reruns``, :func:`is_rerun_of`; the last one holding it) ran again has that run's row, and the table
    names that run's command too."""
    from slax_drake.evaluation.table1 import PAPER_TABLE1

    meta = folder.meta
    source = {p: folder for p in folder.summary["policies"]}
    for rerun in reruns:
        source.update({p: rerun for p in rerun.summary["policies"]})
    lines = [f"Table I protocol in the shelf simulator, profile `{folder.profile}`, {_observation_words(folder)}, "
             f"{meta.get('scenes_per_density', '?')} scenes per density (success %, the paper's figure in parentheses):",
             "", "| policy | 4 objects | 6 objects | 8 objects | 10 objects | All |", "|---|---|---|---|---|---|"]
    for p in _policy_order(source):
        cells = []
        for i, key in enumerate(KEYS):
            rate = (source[p].summary["policies"][p].get(key) or {}).get("success_rate")
            paper = f" ({PAPER_TABLE1[p][i]})" if p in PAPER_TABLE1 else ""
            cells.append(("-" if rate is None else f"{100 * rate:.0f}") + paper)
        lines.append(f"| {_display(p)} | " + " | ".join(cells) + " |")
    used = [f for f in (folder, *reruns) if any(v is f for v in source.values())]
    if len(used) == 1:
        lines += ["", f"Made with `{benchmark_command(folder)}`."]
    else:
        lines += ["", "Made with:", ""]
        for f in used:
            rows = "; ".join(_display(p) for p in _policy_order(source) if source[p] is f)
            lines += [f"- {rows}:", f"  `{benchmark_command(f)}`"]
    return "\n".join(lines) + "\n"


def report_command(folders: list[Path], docs: Path | None, readme: Path | None) -> str:
    parts = ["slax-drake report", *(shlex.quote(str(f)) for f in folders)]
    if docs is not None:
        parts.append(f"--docs {shlex.quote(str(docs))}")
    if readme is not None:
        parts.append(f"--readme {shlex.quote(str(readme))}")
    return " ".join(parts)


def render_pages(folders: list[ResultFolder], command: str) -> dict[str, str]:
    """The results pages (file name under docs/results/ -> Markdown) for the folders, each naming ``command``."""
    sections = {
        "table1": [table1_section(f) for f in folders if f.kind == "table1"],
        "modes": [s for s in [observation_modes_section(folders)] if s],
        "physics": [physics_section(f) for f in folders if f.kind == "physics"],
        "table2": [table2_section(f) for f in folders if f.is_table2],
    }
    notes = {
        "table1": "The paper's figures in parentheses (success %; median steps, IQR). Median steps and action cost "
                  "(pushes + psi suctions) over successful trials. `paper` is the paper's first-order shelf "
                  "simulator taken literally; `station` adds the physical tool's rules (see Concepts).",
        "modes": "The same scenes, policies and distribution model in the two observation modes of `slax-drake "
                 "benchmark --observation`: `privileged` (the objects seen with their true shapes and poses) and "
                 "`camera` (a rendered frame, segmented, the estimator's hypotheses, P_t from the frame).",
        "physics": "`slax-drake benchmark --physics`: the Table I protocol through full Drake trials beside the "
                   "shelf simulator on the same scenes. An action matches when its physical outcome is within "
                   "2 cm and 10 deg of the action model's prediction (each run says which push model).",
        "table2": "The paper's Table II protocol (8, 10 and 12 objects on the physical shelf) run as full Drake "
                  "trials, beside the paper's real-Fetch successes.",
    }
    generated = f"Generated by `{command}` from the result folders named below; do not edit by hand."
    pages = {}
    for kind, parts in sections.items():
        if parts:
            pages[PAGES[kind]] = (f"# {TITLES[kind]}\n\n{notes[kind]}\n\n{generated}\n\n" + "\n".join(parts))
    index = ["# Results", "", "Every table on these pages is generated from the result folders that `slax-drake "
             "benchmark` writes (`table1.json`, `physics.json` and their settings); regenerate them all with:", "",
             "```bash", command, "```", "", "| page | folders |", "|---|---|"]
    for kind, name in PAGES.items():
        if name in pages:
            used = [f for f in folders if (f.kind == "table1" if kind in ("table1", "modes") else
                                           f.is_table2 if kind == "table2" else f.kind == "physics")]
            if kind == "modes":
                used = list(dict.fromkeys(f for row in observation_mode_rows(folders) for f in row[:2]))
            index.append(f"| [{TITLES[kind]}]({name}) | " + ", ".join(f"`{f.path.name}`" for f in used) + " |")
    pages["index.md"] = "\n".join(index) + "\n"
    return pages


def replace_between_markers(path: Path, begin: str, end: str, text: str) -> None:
    """Replaces what stands between the markers ``begin`` and ``end`` of the file at ``path`` (atomically)."""
    content = Path(path).read_text()
    if begin not in content or end not in content:
        raise UserError(f"{path} has no {begin} ... {end} section to replace")
    head, rest = content.split(begin, 1)
    _, tail = rest.split(end, 1)
    write_text_atomic(Path(path), head + begin + "\n" + text + end + tail)


def write_report(folders: list[Path], docs: Path | None = None, readme: Path | None = None) -> list[Path]:
    """Reads the result folders and writes the results pages under ``docs/results/`` and, with ``readme``, the
    README's headline table (first Table I folder). Returns the files written. All folders are read (and refused
    with a UserError) before anything is written."""
    loaded = [load_folder(f) for f in folders]
    if docs is None and readme is None:
        raise UserError("nothing to write: give --docs DIR and/or --readme FILE")
    command = report_command(folders, docs, readme)
    headline = None
    if readme is not None:
        first = next((f for f in loaded if f.kind == "table1"), None)
        if first is None:
            raise UserError("--readme needs a Table I folder (one holding table1.json) for the headline table")
        if not Path(readme).is_file():
            raise UserError(f"{readme}: no such file")
        if not {README_BEGIN, README_END} <= _markers(Path(readme)):
            raise UserError(f"{readme} has no {README_BEGIN} ... {README_END} section to replace")
        headline = headline_table(first, [f for f in loaded if is_rerun_of(f, first)]) + \
            f"\nRegenerate with `{command}`.\n"
        drake = next((f for f in loaded if f.kind == "physics" and not f.is_table2), None)
        if drake is not None and {PHYSICS_BEGIN, PHYSICS_END} <= _markers(Path(readme), (PHYSICS_BEGIN, PHYSICS_END)):
            # the headline physics run (the first physics folder), its section one heading level down
            physics_headline = physics_section(drake).replace("### ", "", 1) + f"\nRegenerate with `{command}`.\n"
        elif drake is not None:
            raise UserError(f"{readme} has no {PHYSICS_BEGIN} ... {PHYSICS_END} section for the physics folder "
                            f"{drake.path}")
        else:
            physics_headline = None
    pages = {}
    if docs is not None:
        blocker = Path(docs) if Path(docs).exists() and not Path(docs).is_dir() else file_in_the_way(Path(docs))
        if blocker is not None:
            raise UserError(f"{docs}: {blocker} is a file, not a folder")
        pages = render_pages(loaded, command)
    written = []
    for name, text in pages.items():
        path = Path(docs) / "results" / name
        write_text_atomic(path, text)
        written.append(path)
    if headline is not None:
        replace_between_markers(Path(readme), README_BEGIN, README_END, headline)
        if physics_headline is not None:
            replace_between_markers(Path(readme), PHYSICS_BEGIN, PHYSICS_END, physics_headline)
        written.append(Path(readme))
    return written


def _markers(path: Path, markers=(README_BEGIN, README_END)) -> set[str]:
    text = path.read_text()
    return {m for m in markers if m in text}
