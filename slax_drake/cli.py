"""The ``slax-drake`` command line: thin wrappers that parse arguments and call library functions.

User errors (bad config, bad file, impossible request) print one line on stderr and exit with code 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from slax_drake.errors import UserError

DEFAULT_CONFIG = "sim_configs/sim_shelf.yaml"


def _cmd_scene(args: argparse.Namespace) -> int:
    from slax_drake.config import load_scenario
    from slax_drake.scene import sample_scene, save_scene

    scenario = load_scenario(args.config)
    scene = sample_scene(scenario, args.objects, args.seed)
    save_scene(scene, args.out)
    print(f"wrote {args.out}: {len(scene.objects)} objects, hidden {scene.target.size} m target at "
          f"({scene.target.center[0]:+.3f}, {scene.target.center[1]:+.3f}) m in the shelf frame")
    if args.png:
        from slax_drake.scene.plot import save_scene_png

        save_scene_png(scene, args.png)
        print(f"wrote {args.png}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="slax-drake",
        description="Lateral-access mechanical search on shelves with the bluction tool (SLAX-RAY), on Drake.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("scene", help="sample a random shelf scene with a completely hidden target",
                       description="Sample a random shelf scene with a completely hidden target (paper Sec. V-A) "
                                   "and write it as JSON, optionally with a picture.")
    p.add_argument("--config", default=DEFAULT_CONFIG, help=f"scenario YAML (default: {DEFAULT_CONFIG})")
    p.add_argument("--objects", type=int, default=8, help="number of occluding objects (default: 8)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    p.add_argument("--out", default="scene.json", help="scene JSON to write (default: scene.json)")
    p.add_argument("--png", help="also write a picture: top-down footprints and the camera's view")
    p.set_defaults(func=_cmd_scene)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except UserError as e:
        print(f"slax-drake {args.command}: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"slax-drake {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
