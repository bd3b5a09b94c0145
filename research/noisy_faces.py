"""How far the estimator's hypotheses, and the suction contact the planner puts on them, are off the true objects,
on rendered Table I frames with and without the L515 noise model. No physics: a cheap look at why suctions on a
noisy frame do not seal.

    python research/noisy_faces.py [--scenes-per-density 10] [--seed 0] [--densities 4,6,8,10]
        [--no-offset-correction] [--no-face-correction]

Per scene (Table I's scenes, ``sim_configs/table1.yaml``, the physics benchmark's seeds): the scene is ray-cast at
the camera's 640x480 (equal to Drake's render to 1e-6 m), optionally through
:func:`~slax_drake.perception.sensor_noise.l515_depth_noise` (seeded by the scene seed, time step 0, as the Drake
trial's DepthNoiseSystem at t = 0), resampled to the policy's 160 px by nearest pixel (as PerceptionSystem does),
segmented by the render's labels and turned into hypotheses by the estimator. Each hypothesis is compared with the
true object its segment shows (only objects with at least ``--min-pixels`` pixels):

- ``front y``: the footprint's nearest y, hypothesis minus truth (mm; negative: the hypothesis is nearer the
  camera than the real front);
- ``centre x``: the footprint centre's x, hypothesis minus truth (mm; occlusion moves it too);
- ``yaw``: boxes whose hypothesis is a box: the yaw difference folded into [-45, 45) deg;
- ``height``: hypothesis minus truth (mm);
- ``gap``: the suction contact of the station action model (``ActionModel.suction_contact`` on the hypothesis,
  the tool's yaw from ``tool_yaw``) and the cup's seal point ``SEAL_PRESS`` past it along the tube's axis; the
  gap is the distance from the seal point along the axis to the true object's surface (mm; positive: the cup
  stops short of the real face, negative: it presses into it);
- ``angle``: between the tube's axis and the true surface's inward normal where the axis meets it (deg).

Then the share of suction contacts the station's suction element would seal on (the cup's tip within
``max_distance`` = 5 mm of the surface and the axis within ``max_angle_deg`` = 30 deg of its normal: a pull at all;
within 2.5 mm: more than half the pull) and the L515 run's range offset (``u * (5 mm + 1 mm/m z)``; u per seed).
Everything is deterministic.
"""

import argparse
import math
from pathlib import Path

import numpy as np
from shapely.geometry import LineString

from slax_drake.config import load_scenario
from slax_drake.evaluation.table1 import scene_seed
from slax_drake.perception.estimator import EstimatorConfig, estimate_objects
from slax_drake.perception.observation import Observation, occluder_segmentation
from slax_drake.perception.sensor_noise import l515_depth_noise
from slax_drake.planning.waypoints import SEAL_PRESS
from slax_drake.shelf.actions import ActionModel
from slax_drake.shelf.rules import ToolConfig
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.raycast import SceneRaycaster
from slax_drake.scene.sampling import sample_scene
from slax_drake.station.scenario import SuctionParameters

REPO = Path(__file__).resolve().parents[1]
WIDTH = 160  # the policies' observation width


def resample(image: np.ndarray, width: int, height: int) -> np.ndarray:
    """Nearest-pixel resampling, as PerceptionSystem does it."""
    h, w = image.shape
    rows = np.clip(np.rint((np.arange(height) + 0.5) * h / height - 0.5), 0, h - 1).astype(int)
    cols = np.clip(np.rint((np.arange(width) + 0.5) * w / width - 0.5), 0, w - 1).astype(int)
    return image[np.ix_(rows, cols)]


def axis_hit(obj, start_xy, axis_xy):
    """(distance along the axis from start to the object's footprint boundary, m, signed; angle in deg between
    the axis and the inward normal there), or None when the axis line misses the footprint."""
    fp = Footprint.of(obj)
    poly = fp.polygon(segments=180)
    a = np.asarray(axis_xy, float)
    p0 = np.asarray(start_xy, float) - 0.5 * a
    line = LineString([tuple(p0), tuple(p0 + 1.0 * a)])
    cut = line.intersection(poly)
    if cut.is_empty:
        return None
    first = min((np.asarray(c) for g in getattr(cut, "geoms", [cut]) for c in g.coords),
                key=lambda c: float((c - p0) @ a))
    t = float((first - p0) @ a) - 0.5
    if obj.shape == "cylinder":
        normal = (first - np.array([fp.x, fp.y]))
    else:
        c, s = math.cos(obj.yaw), math.sin(obj.yaw)
        local = np.array([[c, s], [-s, c]]) @ (first - np.array([fp.x, fp.y]))
        k = int(np.argmax(np.abs(local) / np.array([fp.half_x, fp.half_y])))
        normal = np.array([c, s]) if k == 0 else np.array([-s, c])
        normal = normal * np.sign(local[k])
    normal = normal / np.linalg.norm(normal)
    angle = math.degrees(math.acos(float(np.clip(-normal @ a, -1.0, 1.0))))
    return t, angle


def measure(scenario, densities, per_density, seed, noisy, config, min_pixels):
    tool = ToolConfig.build("station")
    rows = {k: [] for k in ("front", "x", "yaw", "height", "gap", "angle", "offset", "gap_u")}
    size = tuple(scenario.target.sizes[0])
    for n in densities:
        for i in range(per_density):
            s = scene_seed(seed, n, i)
            scene = sample_scene(scenario, scenario.protocol.occluders(n), s, target_size=size)
            cam = scene.camera
            depth, labels = SceneRaycaster(scene, include_target=True).render(cam)
            u = np.random.default_rng((s, 0xACC)).uniform(-1.0, 1.0) if noisy else 0.0
            if noisy:
                depth = l515_depth_noise(depth, cam, s, 0)
                rows["offset"].append(u)
            small = cam.with_resolution(WIDTH, int(round(cam.height * WIDTH / cam.width)))
            depth = resample(depth, small.width, small.height)
            labels = resample(labels, small.width, small.height)
            k = len(scene.objects)
            target = labels == k + 1
            segments = occluder_segmentation(np.where((labels >= 1) & (labels <= k), labels, 0), target)
            frame = Observation(depth, segments, target, small, min_valid_fraction=0.0)
            model = ActionModel(scene.shelf, cam.position[:2], tool)
            for h in estimate_objects(frame, scene.shelf, config):
                if h.pixels < min_pixels:
                    continue
                true = scene.objects[h.segment_id - 1]
                hyp = h.object
                ft, fh = Footprint.of(true), Footprint.of(hyp)
                front = lambda fp: (fp.y - fp.half_x) if fp.shape == "cylinder" else float(fp.corners()[:, 1].min())
                rows["front"].append(front(fh) - front(ft))
                rows["x"].append(fh.x - ft.x)
                rows["height"].append(hyp.size[2] - true.size[2])
                if true.shape == "box" and hyp.shape == "box":
                    d = math.degrees(hyp.yaw - true.yaw)
                    rows["yaw"].append((d + 45.0) % 90.0 - 45.0)
                contact = model.suction_contact(hyp)
                if contact is None:
                    continue
                rows["gap_u"].append(u)
                yaw = model.tool_yaw(hyp, contact[:2])
                a = np.array([-math.sin(yaw), math.cos(yaw)])
                hit = axis_hit(true, np.array(contact[:2]) + SEAL_PRESS * a, a)
                if hit is None:
                    rows["gap"].append(math.inf)
                    rows["angle"].append(math.nan)
                else:
                    rows["gap"].append(hit[0])
                    rows["angle"].append(hit[1])
    return {k: np.array(v, float) for k, v in rows.items()}


def quantiles(values, scale=1000.0):
    v = values[np.isfinite(values)] * scale
    if len(v) == 0:
        return "-"
    p10, p50, p90 = np.percentile(v, [10, 50, 90])
    return f"{p10:+7.1f} {p50:+7.1f} {p90:+7.1f} {np.percentile(np.abs(v), 90):6.1f}"


def densities_arg(text: str) -> list[int]:
    """``--densities``: comma-separated object counts, each at least 1."""
    try:
        values = [int(v) for v in text.split(",")]
    except ValueError:
        values = []
    if not values or min(values) < 1:
        raise argparse.ArgumentTypeError(f"takes comma-separated whole numbers of at least 1 (got {text!r})")
    return values


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes-per-density", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0, help="protocol seed (scene seeds as the physics benchmark)")
    parser.add_argument("--densities", type=densities_arg, default=[4, 6, 8, 10])
    parser.add_argument("--min-pixels", type=int, default=30, help="hypotheses of smaller segments are left out")
    parser.add_argument("--no-offset-correction", action="store_true",
                        help="the estimator without its range-offset correction (EstimatorConfig.correct_range_offset)")
    parser.add_argument("--no-face-correction", action="store_true",
                        help="camera-facing faces at the percentile edge (EstimatorConfig.face_from_points)")
    args = parser.parse_args(argv)
    scenario = load_scenario(REPO / "sim_configs" / "table1.yaml")
    densities = args.densities
    config = EstimatorConfig(correct_range_offset=not args.no_offset_correction,
                             face_from_points=not args.no_face_correction)
    suction = SuctionParameters()
    print(f"Table I scenes, {args.scenes_per_density} per density {densities}, seed {args.seed}; 640x480 -> "
          f"{WIDTH} px; range-offset correction {'on' if config.correct_range_offset else 'off'}, "
          f"face correction {'on' if config.face_from_points else 'off'}")
    print(f"{'quantity':<12} {'noise':<5} {'n':>5} {'p10':>7} {'median':>7} {'p90':>7} {'p90|.|':>6}")
    for noisy in (False, True):
        r = measure(scenario, densities, args.scenes_per_density, args.seed, noisy, config, args.min_pixels)
        tag = "L515" if noisy else "off"
        for name, unit_scale in (("front y mm", 1000.0), ("centre x mm", 1000.0), ("yaw deg", 1.0),
                                 ("height mm", 1000.0), ("gap mm", 1000.0), ("angle deg", 1.0)):
            key = {"front y mm": "front", "centre x mm": "x", "yaw deg": "yaw", "height mm": "height",
                   "gap mm": "gap", "angle deg": "angle"}[name]
            print(f"{name:<12} {tag:<5} {np.isfinite(r[key]).sum():5d} {quantiles(r[key], unit_scale)}")
        gap, angle = r["gap"], r["angle"]
        ok_angle = np.nan_to_num(angle, nan=180.0) < suction.max_angle_deg
        pull = (gap < suction.max_distance) & ok_angle
        half = (gap < suction.max_distance / 2) & ok_angle
        print(f"  suction contacts {len(gap)}: axis misses the object {int(np.sum(~np.isfinite(gap)))}, "
              f"any pull {pull.mean():.0%} ({int(pull.sum())}), over half the pull {half.mean():.0%} "
              f"({int(half.sum())}), cup pressing in (gap <= 0) {np.mean(gap <= 0):.0%}")
        if noisy:
            print(f"  range offset u per scene: median {np.median(r['offset']):+.2f}, "
                  f"{np.mean(r['offset'] < 0):.0%} of scenes nearer than true")
            for lo, hi in ((-1.0, -0.5), (-0.5, 0.0), (0.0, 0.5), (0.5, 1.0)):
                sel = (r["gap_u"] >= lo) & (r["gap_u"] < hi)
                median = 1000 * np.median(gap[sel]) if sel.any() else math.nan
                share = pull[sel].mean() if sel.any() else math.nan
                print(f"  u in [{lo:+.1f}, {hi:+.1f}): contacts {int(sel.sum()):3d}, gap median {median:+.1f} mm, "
                      f"any pull {share:.0%}")


if __name__ == "__main__":
    main()
