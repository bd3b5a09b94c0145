"""The block ``slax-drake trial`` prints at its end: outcome, steps, cost, the files written and how to view them.

A pure function of the trial record (``TrialRecord.data``, the content of ``trial.json``) and the paths written,
so that what a user reads is tested without running Drake.
"""

from __future__ import annotations

from pathlib import Path

from slax_drake.io import plural
from slax_drake.scene.mass import mass_model_words

# What the trial's ``result`` means, as a user reads it.
OUTCOMES = {
    "revealed": "target revealed",
    "horizon": "target not revealed: the horizon of {horizon} actions was spent",
    "no feasible action": "target not revealed: the policy had no feasible action left",
    "no feasible motion": "target not revealed: no candidate action had a collision-free motion",
    "no plan reveals the target": "target not revealed: the policy stopped, no plan of it reveals the target",
    "time limit": "target not revealed: the simulated-time limit (--max-sim-time) ran out",
}


# the robot moved the target when a move brushed it this far (m) or more: said in the outcome line
TARGET_MOVED = 0.01


def outcome_line(data: dict) -> str:
    """One phrase for how the trial ended, with the target's visible share, e.g. "target revealed (93% of it
    visible)", and how far the trial moved the target when a move brushed it ``TARGET_MOVED`` or more."""
    template = OUTCOMES.get(data["result"], "target not revealed: {result}")
    moved = data.get("target_moved_m")
    return (template.format(horizon=data.get("horizon"), result=data["result"])
            + f" ({data['visible_fraction'] * 100:.0f}% of it visible at the end"
            + (f"; a move pushed the target {moved * 100:.1f} cm" if moved is not None and moved >= TARGET_MOVED
               else "") + ")")


_plural = plural


def _size(path: Path) -> str:
    try:
        size = path.stat().st_size
    except OSError:
        return "?"
    return f"{size / 2**20:.1f} MB" if size >= 2**20 else f"{size / 2**10:.0f} kB"


def _cost(cost: float, pushes: int, suctions: int) -> str:
    """The cost with its make-up: 1 per push, the protocol's suction_cost per suction."""
    if not suctions:
        return f"{cost:g}" + (" (1 per push)" if pushes else "")
    psi = (cost - pushes) / suctions
    return f"{cost:g} (1 per push, {psi:g} per suction)"


def why_lines(data: dict, written) -> list[str]:
    """For a trial that ended with no action to execute ("no feasible action" or "no feasible motion"): how many
    candidates the action model refused and the motion planner rejected at the last decision, the most frequent
    reason (stage and kind) and the command that lists every candidate of the scene with its verdict. Empty for
    other endings or a record without the reasons."""
    if data.get("result") not in ("no feasible action", "no feasible motion"):
        return []
    last = (data.get("steps_log") or [{}])[-1]
    reasons = last.get("reasons")
    if reasons is None:
        return []
    refused = len(last.get("refused", ()))
    rejected = len(last.get("rejected", ()))
    head = (f"why:     at the last decision the action model refused {_plural(refused, 'candidate')}, the motion "
            f"planner rejected {rejected}")
    if last.get("feasible_left") and not rejected:
        head += f"; the policy screened out the {_plural(last['feasible_left'], 'feasible one')} left"
        if last.get("screened"):
            head += " (" + ", ".join(f"{why}: {n}" for why, n in sorted(last["screened"].items(),
                                                                       key=lambda kv: (-kv[1], kv[0]))) + ")"
    if last.get("stop_reason"):  # after a rejection: what the policy said when asked again without it
        head += (f"; then the policy had none left ({last['stop_reason']})" if rejected
                 else f" (the policy: {last['stop_reason']})")
    lines = [head]
    if reasons:
        top = reasons[0]
        lines.append(f"  most frequent: {top['stage']}: {top['kind']} ({_plural(top['count'], 'candidate')})"
                     + "".join(f"; then {r['stage']}: {r['kind']} ({r['count']})" for r in reasons[1:3]))
    record = next((Path(p) for p in written if Path(p).name == "trial.json"), None)
    lines.append(f"  every candidate with its verdict (action model, then planner, on the true scene as it stood at "
                 f"the last decision): slax-drake check-action --from-trial "
                 f"{record.parent if record is not None else 'OUT'} --all")
    return lines


def trial_summary(data: dict, written: list[Path], html: str | Path | None = None,
                  meshcat_url: str | None = None) -> str:
    """The trial's closing block (lines without a trailing newline).

    ``data``: the trial record; ``written``: the files :func:`slax_drake.systems.trial.write_trial` wrote;
    ``html``: the HTML replay's path when one was asked for; ``meshcat_url``: the live view's address when
    ``--meshcat`` served one (it closes with the process, and the block says so).
    """
    actions = data["actions"]
    pushes = sum(1 for a in actions if a["type"] == "push")
    lines = ["", "== trial summary ==",
             f"outcome: {outcome_line(data)}",
             f"steps:   {_plural(data['steps'], 'action')} ({_plural(pushes, 'push')}, "
             f"{_plural(len(actions) - pushes, 'suction')}) of at most {data['horizon']}"]
    for k, a in enumerate(actions, start=1):
        params = f"d={a['d']:+.3f} m" if a["type"] == "push" else f"dx={a['dx']:+.3f} m, to y={a['dz']:+.3f} m"
        rejected = len(a["rejected_before"])
        who = a["object"] + (f" (= {a['true_object']})" if a.get("true_object") and a["true_object"] != a["object"] else "")
        lines.append(f"  {k}. {a['type']} {who} ({params}): motion {a['motion']['duration_s']:.1f} s, "
                     f"planned in {a['planning_s']:.2f} s"
                     + (f" after {_plural(rejected, 'rejected candidate')}" if rejected else ""))
    lines.extend(why_lines(data, written))
    lines.append(f"cost:    {_cost(data['cost'], pushes, len(actions) - pushes)}")
    rtf = data.get("real_time_factor")
    lines.append(f"time:    simulated {data['sim_time_s']:.1f} s in {data['wall_s']:.1f} s of wall time"
                 + (f" (real-time factor {rtf:.1f})" if rtf else ""))
    profile = f"the '{data['profile']}' profile" if data.get("profile") else "the action model's rules"
    if data.get("tool_rules"):
        lines.append(f"rules:   {profile}, with " + ", ".join(f"{k}={v}" for k, v in data["tool_rules"].items())
                     + " (the station cup's limits and --tool-rule)")
    else:
        lines.append(f"rules:   {profile}")
    if "mass_model" in data:  # a record from before it was kept names none
        lines.append(f"masses:  {mass_model_words(data['mass_model'])}")

    written = [Path(p) for p in written]
    html_path = Path(html) if html else None
    pngs = sorted(p for p in written if p.suffix == ".png")
    lines.append("files:")
    for p in written:
        if p.name == "trial.json":
            lines.append(f"  {p}  the record: actions, 1D support per step, executed joint trajectory, "
                         "final object poses")
        elif p.name == "scene.json":
            lines.append(f"  {p}  the initial scene")
    if pngs:
        span = str(pngs[0]) if len(pngs) == 1 else f"{pngs[0]} .. {pngs[-1].name}"
        lines.append(f"  {span}  per decision: depth, labels with the chosen action, target distribution "
                     f"({_plural(len(pngs), 'image')})")
    if html_path is not None and html_path in written:
        lines.append(f"  {html_path}  the Meshcat replay ({_size(html_path)}, self-contained)")

    lines.append("view:")
    if html_path is not None and html_path in written:
        lines.append(f"  open {html_path} in a web browser ({html_path.resolve().as_uri()}); it needs no server "
                     "and plays the trial once (Open Controls > Animations: play, pause, time)")
    else:
        trial_json = next((p for p in written if p.name == "trial.json"), None)
        where = str(trial_json.parent) if trial_json is not None else "OUT"
        lines.append(f"  slax-drake view-trial {where} writes a replay that opens in any web browser, from the "
                     "trial's records (no simulation)")
    if pngs:
        lines.append(f"  the step images in any image viewer, e.g. {pngs[0]}")
    if meshcat_url:
        lines.append(f"  the live view at {meshcat_url} closes when this command ends (--html writes a replay that lasts)")
    return "\n".join(lines)
