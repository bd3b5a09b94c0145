"""Evidence for the action model's rule variants: for the scenario's profile (sim_configs/table1.yaml: paper), each
strict rule alone and all strict rules together (slax_drake.shelf.rules.STRICT_RULES), on the Table I scenes (protocol seed 0, the first N of each density), prints

- the feasible actions per state (mean count at the initial state, pushes and suctions),
- the fraction of scenes where some occluder (an object hiding part of the target) can be pushed / suctioned,
- the fraction of scenes a single action reveals (the one-step optimum: exact, every candidate is checked
  against the simulator's own visibility test), with pushes only (P) and with suctions too (P+S).

    python research/rule_ablation.py [--scenes 10] [--densities 4,6,8,10]
"""

import argparse
import time

import numpy as np

from slax_drake.config import load_scenario
from slax_drake.shelf.actions import ActionModel, Push, apply_action
from slax_drake.shelf.rules import STRICT_RULES
from slax_drake.evaluation.table1 import scene_seed
from slax_drake.shelf.tool import tool_config
from slax_drake.shelf.visibility import TargetOcclusion
from slax_drake.scene import sample_scene
from slax_drake.scene.sampling import shelf_of


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", type=int, default=10, help="scenes per density")
    ap.add_argument("--densities", default="4,6,8,10")
    args = ap.parse_args()
    sc = load_scenario("sim_configs/table1.yaml")
    densities = [int(v) for v in args.densities.split(",")]
    scenes = [sample_scene(sc, d, scene_seed(0, d, i), target_size=tuple(sc.target.sizes[0]))
              for d in densities for i in range(args.scenes)]
    occlusions = [TargetOcclusion(s, threshold=sc.target.visibility_threshold) for s in scenes]
    variants = [(f"{sc.profile} profile", {})] + [(f"strict {k}={v}", {k: v}) for k, v in STRICT_RULES.items()]
    variants.append(("all strict", dict(STRICT_RULES)))
    print(f"{len(scenes)} scenes ({args.scenes} each of {densities} objects)")
    print(f"{'variant':>36} | pushes/state | suctions/state | occluder pushable | occluder suctionable | "
          "1-step P | 1-step P+S")
    for label, overrides in variants:
        t0 = time.perf_counter()
        n_p, n_s, occ_p, occ_s, one_p, one_s = [], [], 0, 0, 0, 0
        for s, occ in zip(scenes, occlusions):
            model = ActionModel(shelf_of(sc), s.camera.position, tool_config(sc, **overrides))
            feasible = model.enumerate(s.objects, fixed=(s.target.as_object(),)).feasible
            pushes = [a for a in feasible if isinstance(a, Push)]
            sucs = [a for a in feasible if not isinstance(a, Push)]
            n_p.append(len(pushes))
            n_s.append(len(sucs))
            occluders = {o.name for o in s.objects if occ.hidden_bits(o)}
            occ_p += any(a.name in occluders for a in pushes)
            occ_s += any(a.name in occluders for a in sucs)
            reveal_p = any(occ.revealed(apply_action(s.objects, a)) for a in pushes)
            one_p += reveal_p
            one_s += reveal_p or any(occ.revealed(apply_action(s.objects, a)) for a in sucs)
        n = len(scenes)
        print(f"{label:>36} | {np.mean(n_p):12.1f} | {np.mean(n_s):14.1f} | {occ_p / n:17.0%} | "
              f"{occ_s / n:20.0%} | {one_p / n:8.0%} | {one_s / n:10.0%}   ({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
