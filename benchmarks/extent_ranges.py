"""How often the estimator's extent range holds the true footprint, on ray-cast frames of the simulated shelf
(the shelf simulator's camera mode: label segmentation), per density, clean or with the L515 noise model.

    python benchmarks/extent_ranges.py [--scenes 10] [--width 160] [--noise] [--tail] [--fit]
        [--second-view LIFT:PITCH]

Scenes: ``sim_configs/sim_shelf.yaml``, 4, 6, 8 and 10 objects, seeds 1000..1000+N-1. A seen object counts as
held when at most 1 cm^2 of its true footprint lies outside the range's farthest rectangle grown by 5 mm. Also
printed: the mean reach of the range beyond the observed part along the axis nearest the viewing direction (m),
and the true depth beyond the observed part, for the objects held.

``--tail``: also, per density, where the true edges lie in their ranges: over every edge of every seen box or
cylinder whose range reaches more than 2 cm past the observed part, the share of the range the true footprint
reaches past the observed part (0: the observed part was the whole object along that edge; 1: the farthest the
frame allows), and the share of those edges at least each of the shares
``slax_drake.policies.extents.EXTENT_SHARE_TAIL`` lists (the tail slax-belief's ``extent_prior`` and ``extent_risk``
options read; measured with ``--scenes 30 --tail``).

``--fit``: also, per density, how the hypotheses themselves differ from the objects they show: how many have
another shape (a box taken for a cylinder or the reverse), the boxes' yaw error (modulo a quarter turn; median,
90th percentile, share over 10 degrees), how far a hypothesis reaches outside its object (the farthest corner,
mm; median and 90th percentile, boxes and cylinders apart) and how much of the object's footprint it leaves out
(cm^2; median, 90th percentile). ``--second-view LIFT:PITCH`` with ``--fit``: the same for the hypotheses grown by
what a second frame shows of their objects, the camera raised LIFT m and pitched down PITCH deg (the frames
associated by their labels; :func:`~slax_drake.perception.tracking.fused_box`), and how many were grown.
"""

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from slax_drake.config import load_scenario
from slax_drake.perception.estimator import estimate_objects
from slax_drake.perception.observation import labelled_frame
from slax_drake.perception.sensor_noise import l515_depth_noise
from slax_drake.perception.tracking import fused_box
from slax_drake.scene import sample_scene
from slax_drake.scene.camera import camera_pose
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.raycast import SceneRaycaster

REPO = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=int, default=10, help="scenes per density (seeds 1000..)")
    parser.add_argument("--width", type=int, default=160, help="image width (px); the height keeps the aspect")
    parser.add_argument("--noise", action="store_true", help="the L515 noise model on the depth")
    parser.add_argument("--tail", action="store_true", help="also where the true edges lie in their ranges")
    parser.add_argument("--fit", action="store_true", help="also how the hypotheses differ from their objects")
    parser.add_argument("--second-view", default=None, metavar="LIFT:PITCH",
                        help="with --fit: also the hypotheses grown by a second frame from a raised, tilted camera")
    args = parser.parse_args(argv)
    second_view = None
    if args.second_view is not None:
        try:
            lift, pitch = (float(v) for v in args.second_view.split(":"))
        except ValueError:
            parser.error(f"--second-view must be LIFT:PITCH in metres and degrees (got {args.second_view})")
        second_view = (lift, pitch)
    if args.scenes < 1 or args.width < 16:
        parser.error("--scenes must be at least 1 and --width at least 16")
    scenario = load_scenario(REPO / "sim_configs" / "sim_shelf.yaml")
    print(f"width {args.width} px, {'L515 noise' if args.noise else 'clean'}, {args.scenes} scenes per density")
    print(f"{'objects':>7} {'seen':>5} {'held':>5} {'share':>6} {'reach m':>8} {'true m':>7}")
    for n in (4, 6, 8, 10):
        seen = held = 0
        reach, true_depth, shares = [], [], []
        fits = {"shape": 0, "yaw": [], "out box": [], "out cylinder": [], "missed": []}
        grown = {"shape": 0, "yaw": [], "out box": [], "out cylinder": [], "missed": [], "count": 0}
        for seed in range(1000, 1000 + args.scenes):
            scene = sample_scene(scenario, n, seed)
            camera = scene.camera.with_resolution(args.width, int(round(scene.camera.height * args.width
                                                                         / scene.camera.width)))
            depth, labels = SceneRaycaster(scene, include_target=True).render(camera)
            if args.noise:
                depth = l515_depth_noise(depth, camera, seed, 0)
            frame = labelled_frame(depth, labels, n, camera)
            second = {}
            if second_view is not None:
                raised = camera.position + np.array([0.0, 0.0, second_view[0]])
                other = dataclasses.replace(camera, X_SC=camera_pose(raised, second_view[1]))
                other_frame = labelled_frame(*SceneRaycaster(scene, include_target=True).render(other), n, other)
                second = {h2.segment_id: h2.object for h2 in estimate_objects(other_frame, scene.shelf)}
            for h in estimate_objects(frame, scene.shelf):
                truth = Footprint.of(scene.objects[h.segment_id - 1])
                extent = h.uncertainty.extent
                seen += 1
                shares += edge_shares(truth, extent)
                fit_errors(scene.objects[h.segment_id - 1], h.object, fits)
                if second_view is not None:
                    fused = fused_box(second[h.segment_id], h.object) if h.segment_id in second else None
                    grown["count"] += fused is not None
                    fit_errors(scene.objects[h.segment_id - 1], fused if fused is not None else h.object, grown)
                if truth.polygon().difference(extent.most().polygon().buffer(0.005)).area > 1e-4:
                    continue
                held += 1
                c, s = np.cos(extent.yaw), np.sin(extent.yaw)
                axes = np.array([[c, s], [-s, c]])
                view = np.array([truth.x, truth.y]) - camera.position[:2]
                k = int(np.argmax(np.abs(axes @ view)))
                far = 1 if (axes @ view)[k] > 0 else 0  # the far edge along that axis: hi when it points away
                corners = truth.polygon().exterior.coords
                along = np.array(corners) @ axes[k]
                if far:
                    reach.append(extent.most_hi[k] - extent.least_hi[k])
                    true_depth.append(max(along.max() - extent.least_hi[k], 0.0))
                else:
                    reach.append(extent.least_lo[k] - extent.most_lo[k])
                    true_depth.append(max(extent.least_lo[k] - along.min(), 0.0))
        share = held / max(seen, 1)
        print(f"{n:>7} {seen:>5} {held:>5} {share:>6.3f} {np.mean(reach):>8.3f} {np.mean(true_depth):>7.3f}")
        if args.tail:
            tail = np.array(shares)
            points = ", ".join(f"{t:g}: {(tail >= t).mean():.3f}" for t in TAIL_POINTS)
            print(f"{'':>7} {len(tail)} edges reaching over 2 cm; share of them reaching at least ... {points}")
        if args.fit:
            yaw = np.array(fits["yaw"])

            def q(values, scale):
                v = np.array(values) * scale
                return f"{np.median(v):.1f} / {np.quantile(v, 0.9):.1f}" if len(v) else "-"

            print(f"{'':>7} another shape {fits['shape']} of {seen}; box yaw error (deg) {q(yaw, 1)}, over 10 deg "
                  f"{(yaw > 10).mean():.2f}; outside the object (mm) boxes {q(fits['out box'], 1e3)}, cylinders "
                  f"{q(fits['out cylinder'], 1e3)}; object left out (cm^2) {q(fits['missed'], 1e4)}, "
                  f"mean {np.mean(fits['missed']) * 1e4:.1f}")
            if second_view is not None:
                print(f"{'':>7} with the second view: {grown['count']} grown; outside the object (mm) boxes "
                      f"{q(grown['out box'], 1e3)}; object left out (cm^2) {q(grown['missed'], 1e4)}, "
                      f"mean {np.mean(grown['missed']) * 1e4:.1f}")
    return 0


TAIL_POINTS = (0.02, 0.05, 0.1, 0.25, 0.5, 0.75, 1.0)


def fit_errors(true_object, hypothesis, fits: dict) -> None:
    """Adds ``hypothesis``'s differences from ``true_object`` to ``fits`` (see ``--fit``)."""
    from shapely.geometry import Point

    truth, fitted = Footprint.of(true_object).polygon(), Footprint.of(hypothesis).polygon()
    if hypothesis.shape != true_object.shape:
        fits["shape"] += 1
    elif true_object.shape == "box":
        turn = (hypothesis.yaw - true_object.yaw) % (np.pi / 2)
        fits["yaw"].append(float(np.degrees(min(turn, np.pi / 2 - turn))))
    out = max(truth.exterior.distance(Point(c)) if not truth.contains(Point(c)) else 0.0
              for c in fitted.exterior.coords)
    fits[f"out {true_object.shape}"].append(out)
    fits["missed"].append(truth.difference(fitted).area)


def edge_shares(truth: Footprint, extent) -> list[float]:
    """For each edge of ``extent`` (an ExtentRange) whose range reaches more than 2 cm past the observed part, the
    share of that reach the true footprint ``truth`` extends past the observed part (0 when it does not)."""
    c, s = np.cos(extent.yaw), np.sin(extent.yaw)
    corners = np.asarray(truth.polygon().exterior.coords)
    out = []
    for k, axis in enumerate((np.array([c, s]), np.array([-s, c]))):
        along = corners @ axis
        for room, past in ((extent.most_hi[k] - extent.least_hi[k], along.max() - extent.least_hi[k]),
                           (extent.least_lo[k] - extent.most_lo[k], extent.least_lo[k] - along.min())):
            if room > 0.02:
                out.append(max(float(past), 0.0) / room)
    return out


if __name__ == "__main__":
    raise SystemExit(main())
