"""Per-scene evidence for an oracle's failed Table I trials: for each failed trial of a benchmark folder, the
objects that hide the target (and how much of it each hides alone), and, for each of them, what the action model
says about pushing it either way in the initial state (the longest push and what stops it, or the rule that
refuses it); optionally a top-down picture of each scene. Prints Markdown.

    python research/oracle_failures.py results/table1 [--policy oracle-p] [--densities 8,10]
        [--config sim_configs/table1.yaml] [--pictures docs/results/oracle_p_failures] [--variant NAME]

``--variant``: a folder made by benchmarks/table1_ablation.py under one of its variants (OUT/<variant>): the
variant's scenario changes are applied before the scenes are drawn again (its rules come from the trial files).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from slax_drake.config import load_scenario
from slax_drake.errors import UserError
from slax_drake.evaluation.table1 import protocol_scene, scene_seed
from slax_drake.evaluation.trial_records import read_trial_records
from slax_drake.shelf.actions import ActionModel, Push
from slax_drake.shelf.tool import tool_config
from slax_drake.shelf.visibility import TargetOcclusion
from slax_drake.scene.sampling import shelf_of


def push_evidence(model: ActionModel, objects, fixed, name: str) -> list[str]:
    """One phrase per direction: the longest feasible push and why it stops there, or why none is feasible."""
    cands = model.enumerate(objects, fixed=fixed, suctions=False, only={name})
    out = []
    for sign, label in ((+1, "+x"), (-1, "-x")):
        longest = max((abs(a.d) for a in cands.feasible if isinstance(a, Push) and (a.d > 0) == (sign > 0)),
                      default=None)
        why = [r.reason for r in cands.rejected if r.what.startswith(f"push {name} {label}")]
        if longest is None:
            out.append(f"{label}: refused ({'; '.join(why) or 'no candidate'})")
        else:
            stop = next((w for w in why if "would hit" in w), "")
            out.append(f"{label}: up to {longest:.3f} m" + (f" ({stop.split('would hit ')[-1]})" if stop else ""))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", help="a benchmark output folder (holding trials/<policy>/)")
    ap.add_argument("--policy", default="oracle-p")
    ap.add_argument("--densities", default="8,10")
    ap.add_argument("--config", default="sim_configs/table1.yaml")
    ap.add_argument("--pictures", default=None, help="write a top-down PNG of each failing scene here")
    ap.add_argument("--variant", default=None,
                    help="the folder is a variant of benchmarks/table1_ablation.py: apply its scenario changes")
    args = ap.parse_args()
    scenario = load_scenario(args.config)
    if args.variant:
        sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # table1_ablation's folder
        from table1_ablation import VARIANTS, scenario_with

        if args.variant not in VARIANTS:
            print(f"error: --variant {args.variant!r} is not a variant of benchmarks/table1_ablation.py (known: "
                  f"{', '.join(VARIANTS)})", file=sys.stderr)
            raise SystemExit(2)
        scenario = scenario_with(scenario, VARIANTS[args.variant][3])
    densities = [int(v) for v in args.densities.split(",")]
    try:
        trials = read_trial_records(args.folder, args.policy, missing_ok=True)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        raise SystemExit(2)
    for trial in trials.values():
        if trial["success"] or trial["density"] not in densities:
            continue
        profile = trial.get("profile", "station")
        model = ActionModel(shelf_of(scenario), scenario.camera.position,
                            tool_config(scenario, profile, **(trial.get("tool_rules") or {})))
        n, index = trial["density"], trial["index"]
        scene = protocol_scene(scenario, n, scene_seed(scenario.protocol.seed, n, index))
        occlusion = TargetOcclusion(scene, threshold=scenario.target.visibility_threshold)
        fixed = (scene.target.as_object(),)
        occluders = [(o, occlusion.hidden_bits(o).bit_count() / max(1, occlusion.n)) for o in scene.objects]
        occluders = sorted([(o, f) for o, f in occluders if f > 0], key=lambda t: -t[1])
        need = occlusion.min_objects_to_move(scene.objects)
        print(f"- **{n} objects, scene {index}** ({profile} profile; {trial['reason']}, search "
              f"{trial.get('oracle_status', '?')}; target {100 * trial['visible_fraction']:.0f} % visible, at least "
              f"{need} object(s) must move):")
        for obj, fraction in occluders:
            print(f"  - {obj.name} hides {100 * fraction:.0f} % alone: "
                  + "; ".join(push_evidence(model, scene.objects, fixed, obj.name)))
        if args.pictures:
            from slax_drake.scene.plot import save_scene_png

            out = Path(args.pictures) / f"{args.policy}_{n:02d}_{index:04d}.png"
            out.parent.mkdir(parents=True, exist_ok=True)
            save_scene_png(scene, out)
            print(f"  - picture: `{out}`")


if __name__ == "__main__":
    main()
