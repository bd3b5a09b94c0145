"""``slax-drake occupancy``: the hidden target placements of a scene and their 2D / 1D distributions."""

from __future__ import annotations

import argparse


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "occupancy",
        help="ground-truth target occupancy of a scene (hidden placements, 2D and 1D distributions)",
        description="Find every hidden placement of the scene's target on a grid and write hidden_xy, p2d and "
        "p1d to an npz file, optionally with a picture.",
    )
    p.add_argument("scene", help="scene JSON (from `slax-drake scene`)")
    p.add_argument("--out", default="occ.npz", help="npz to write (default: occ.npz)")
    p.add_argument("--png", help="also write a picture: depth with p2d, p1d below, top-down placements")
    p.add_argument("--grid-step", type=float, default=0.005, help="placement grid in metres, at most half the target's smallest side (default: 0.005)")
    p.add_argument("--surface-spacing", type=float, default=0.005,
                   help="spacing of the target's surface samples in metres, at most half the target's smallest side "
                   "(default: 0.005)")
    p.set_defaults(func=run)


def meaningful_step_limit(target_size) -> float:
    """The coarsest placement grid or surface-sample spacing (metres) whose result still means something for a
    target of ``target_size`` [x, y, z] (metres): half its smallest side, so that every placement the target fits
    into is on the grid and every face has samples inside its edges."""
    return 0.5 * min(float(v) for v in target_size)


def run(args: argparse.Namespace) -> int:
    import io

    import numpy as np

    from slax_drake.errors import SceneFileError, UserError
    from slax_drake.occupancy import compute_occupancy
    from slax_drake.occupancy.hidden import occupancy_memory_bytes
    from slax_drake.resources import check_memory
    from slax_drake.scene import load_scene
    from slax_drake.io import plural, write_bytes_atomic

    scene = load_scene(args.scene)
    if scene.target is None:
        raise SceneFileError(f"{args.scene}: the scene has no target, so there is no target size to place")
    if not (args.grid_step > 0 and args.surface_spacing > 0):
        raise UserError("--grid-step and --surface-spacing must be positive lengths in metres")
    limit = meaningful_step_limit(scene.target.size)
    for option, value in (("--grid-step", args.grid_step), ("--surface-spacing", args.surface_spacing)):
        if value > limit:
            raise UserError(f"{option} {value:g} m is coarser than half the target's smallest side "
                            f"({limit:g} m of the {min(scene.target.size):g} m side), so hidden placements would "
                            f"be missed or judged from too few surface samples: use at most {limit:g} m")
    check_memory(occupancy_memory_bytes(scene, [scene.target.size], args.grid_step, args.surface_spacing),
                 f"--grid-step {args.grid_step:g} m with --surface-spacing {args.surface_spacing:g} m",
                 "use a coarser grid or spacing (the default is 0.005 m for both)")
    occ = compute_occupancy(scene, scene.target.size, args.grid_step, None, args.surface_spacing)
    buf = io.BytesIO()
    np.savez_compressed(buf, hidden_xy=occ.hidden_xy, p2d=occ.p2d, p1d=occ.p1d,
                        target_size=np.array(occ.target_size), grid_step=occ.grid_step)
    write_bytes_atomic(args.out, buf.getvalue())
    print(f"wrote {args.out}: {plural(occ.num_hidden, 'hidden placement')} of the {scene.target.size} m target "
          f"(grid {args.grid_step} m), p2d {occ.p2d.shape}")
    if args.png:
        from slax_drake.occupancy.plot import save_occupancy_png

        save_occupancy_png(scene, occ, args.png)
        print(f"wrote {args.png}")
    return 0
