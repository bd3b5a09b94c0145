"""``slax-drake scene``: sample a random shelf scene with a completely hidden target."""

from __future__ import annotations

import argparse

from slax_drake import arguments
from slax_drake.config import DEFAULT_CONFIG
from slax_drake.io import plural


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "scene",
        help="sample a random shelf scene with a completely hidden target",
        description="Sample a random shelf scene with a completely hidden target (paper Sec. V-A) "
        "and write it as JSON, optionally with a picture.",
    )
    p.add_argument("--config", default=DEFAULT_CONFIG, help=f"scenario YAML (default: {DEFAULT_CONFIG})")
    p.add_argument("--objects", type=int, default=8, help="number of occluding objects (default: 8)")
    p.add_argument("--seed", type=arguments.seed, default=0, help="random seed (default: 0)")
    p.add_argument("--out", default="scene.json", help="scene JSON to write (default: scene.json)")
    p.add_argument("--png", help="also write a picture: top-down footprints and the camera's view")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from slax_drake.config import load_scenario
    from slax_drake.scene import sample_scene, save_scene

    scenario = load_scenario(args.config)
    scene = sample_scene(scenario, args.objects, args.seed)
    save_scene(scene, args.out)
    print(
        f"wrote {args.out}: {plural(len(scene.objects), 'object')}, hidden {scene.target.size} m target at "
        f"({scene.target.center[0]:+.3f}, {scene.target.center[1]:+.3f}) m in the shelf frame"
    )
    if args.png:
        from slax_drake.scene.plot import save_scene_png

        save_scene_png(scene, args.png)
        print(f"wrote {args.png}")
    return 0
