"""A station's precomputed reach map and the conservative lookup the action model's ``reach_map`` rule reads.

The map (computed by :mod:`slax_drake.planning.reach`, committed under ``models/reach/``) holds, on a grid of the
shelf frame S (x right, y into the shelf; metres) over the bay floor, whether the motion planner found a
collision-free IK solution from the observation pose, on the empty shelf, for each layer:

- ``push+x`` / ``push-x``: the blade inserted for a push toward +x / -x whose action parameter q is (x, y) (the
  blade lane's centre and the blade tip's depth; the action model's Push.q);
- ``cup``: the cup at the seal of a suction with the tube along y (yaw 0) whose contact is (x, y), at the height
  ``heights["cup"]``;
- optional turned-cup layers ``cup@-30/3cm`` ... ``cup@+30/10cm`` (:data:`TURNED_CUP_YAWS_DEG` x
  :data:`TURNED_CUP_HEIGHTS`): the same with the tool turned that many degrees about S z (the action's yaw), the
  contact at that height. :meth:`ReachMap.refuses_cup` refuses a turned suction only when the layers of every
  yaw node and every height node around its yaw and contact height (the yaw-0 node is ``cup``, at its one height)
  exist and refuse its contact;
- optional release layers ``back off`` and ``retract`` (:data:`RELEASE_LAYERS`): a yaw-0 suction whose cup releases
  the object with its contact at (x, y), at the height ``heights["back off"]``: the cup backed off along the tube,
  and the tool drawn back in front of the opening (at either approach margin). :meth:`ReachMap.refuses_release`
  refuses a release where either layer refuses it.

:meth:`ReachMap.refuses` is conservative: a point is refused only when every grid node of every cell within
``margin`` of it (the cells its neighbourhood touches) is unreachable, so a refused point lies inside a region
where the planner found nothing; points off the grid are never refused.

Optional hold layers ``hold@-30/3cm`` ... ``hold@+30/36cm`` (:data:`HOLD_YAWS_DEG` x :data:`HOLD_HEIGHTS`), on
their own grid (the map's ``xs`` and ``hold_ys``, which reaches from 0.27 m in front of the opening to the back of
the bay): the cup tip itself (not a contact) at (x, y) and that height (m above the support), the tool turned that
many degrees about S z, the blade up and suction on, as while the cup holds an object. These are the poses of a
lifted suction's carry (pulled out, translated across in front of the opening or inside the bay, pushed in) and of
its lowered placement. :meth:`ReachMap.refuses_hold` refuses a hold pose only when the layers of every yaw node
around its yaw and every height node spanning its height range exist and refuse it.

Optional pre-approach layers ``approach@-30/3cm`` ... (:data:`APPROACH_YAWS_DEG` x :data:`APPROACH_HEIGHTS`), on a
grid of their own (``approach_xs``, wide enough for a turned tool's pre-approach far to the side, and
``approach_ys``, the two rows of the tool's tip at the planner's approach margins in front of the opening): the cup
tip there, the tool turned, the blade up, suction off, as the planner's first waypoint of a suction. :meth:`ReachMap.refuses_approach` refuses a
pre-approach only where every layer around its yaw and height refuses it.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from pathlib import Path

import numpy as np

LAYERS = ("push+x", "push-x", "cup")
# Optional layers of a yaw-0 suction's release, (x, y) the cup's contact where it releases the object: the cup
# backed off along the tube, and the tool retracted in front of the opening (the same for every y)
RELEASE_LAYERS = ("back off", "retract")
TURNED_CUP_YAWS_DEG = (-30, -20, -10, 10, 20, 30)  # the tool's yaw of the optional turned-cup layers (deg)
TURNED_CUP_HEIGHTS = (0.03, 0.06, 0.10)  # their contact heights (m above the support)
HOLD_YAWS_DEG = (-30, -15, 0, 15, 30)  # the tool's yaw of the optional hold layers (deg)
HOLD_HEIGHTS = (0.03, 0.11, 0.20, 0.28, 0.36)  # the cup tip's height of the hold layers (m above the support;
# a carry lifted over a tall object rises to about 0.35 m)
APPROACH_HEIGHTS = HOLD_HEIGHTS[:3]  # those of the pre-approach layers (a contact is at most 0.2 m high)
# the tool's yaw of the optional pre-approach layers (deg; finer than the hold layers': in front of the opening the
# reach ends sharply with the turn, and a layer there is 2 rows)
APPROACH_YAWS_DEG = tuple(range(-30, 31, 5))


def turned_cup_layer(yaw_deg: int, height: float) -> str:
    """The name of the turned-cup layer at ``yaw_deg`` (deg, not 0) and contact ``height`` (m)."""
    return f"cup@{yaw_deg:+d}/{round(height * 100):d}cm"


def turned_cup_params(layer: str) -> tuple[float, float]:
    """(yaw in rad, contact height in m) of a turned-cup layer's name."""
    yaw, height = layer[len("cup@"):].split("/")
    return math.radians(float(yaw)), float(height[:-2]) / 100.0


def turned_cup_layers() -> tuple[str, ...]:
    return tuple(turned_cup_layer(d, h) for d in TURNED_CUP_YAWS_DEG for h in TURNED_CUP_HEIGHTS)


def hold_layer(yaw_deg: int, height: float, family: str = "hold") -> str:
    """The name of the hold (or, with ``family`` "approach", pre-approach) layer at tool yaw ``yaw_deg`` (deg) and
    cup height ``height`` (m)."""
    return f"{family}@{yaw_deg:+d}/{round(height * 100):d}cm"


def hold_params(layer: str) -> tuple[float, float]:
    """(yaw in rad, cup height in m) of a hold or pre-approach layer's name."""
    yaw, height = layer.split("@", 1)[1].split("/")
    return math.radians(float(yaw)), float(height[:-2]) / 100.0


def hold_layers(family: str = "hold") -> tuple[str, ...]:
    """Every hold (or pre-approach) layer's name, yaw 0 first, then +-30 deg, then the others (the order the map is
    computed in)."""
    order = sorted(family_yaws_deg(family), key=lambda d: (d != 0, -abs(d), d))
    heights = HOLD_HEIGHTS if family == "hold" else APPROACH_HEIGHTS
    return tuple(hold_layer(d, h, family) for d in order for h in heights)


def family_yaws_deg(family: str) -> tuple[int, ...]:
    """The yaw nodes (deg) of the hold layers (``family`` "hold") or of the pre-approach layers ("approach")."""
    return HOLD_YAWS_DEG if family == "hold" else APPROACH_YAWS_DEG


def hold_height_span(z_lo: float, z_hi: float) -> tuple[int, int] | None:
    """(first, last) indices of the :data:`HOLD_HEIGHTS` nodes that span heights ``z_lo`` .. ``z_hi`` (m): from the
    node at or below ``z_lo`` to the one at or above ``z_hi``; None when the range leaves the nodes."""
    h = HOLD_HEIGHTS
    if not (h[0] - 1e-9 <= z_lo <= z_hi + 1e-12 and z_hi <= h[-1] + 1e-9):
        return None
    lo = max(k for k, v in enumerate(h) if v <= z_lo + 1e-9)
    hi = min(k for k, v in enumerate(h) if v >= z_hi - 1e-9)
    return lo, hi


def _refuses_on(xs: np.ndarray, ys: np.ndarray, values: np.ndarray, x: float, y: float, margin: float) -> bool:
    """True when every node of ``values`` (len(ys), len(xs)) around (x +- margin, y +- margin) is False; False off
    the grid or where any such node is True."""
    if not (xs[0] - 1e-9 <= x <= xs[-1] + 1e-9 and ys[0] - 1e-9 <= y <= ys[-1] + 1e-9):
        return False
    i0 = max(0, int(np.searchsorted(xs, x - margin - 1e-9, side="right")) - 1)
    i1 = min(len(xs) - 1, int(np.searchsorted(xs, x + margin + 1e-9, side="left")))
    j0 = max(0, int(np.searchsorted(ys, y - margin - 1e-9, side="right")) - 1)
    j1 = min(len(ys) - 1, int(np.searchsorted(ys, y + margin + 1e-9, side="left")))
    return not bool(values[j0:j1 + 1, i0:i1 + 1].any())


def summed_area(values: np.ndarray) -> np.ndarray:
    """The summed-area table of a layer's reached nodes: (rows + 1, columns + 1), zeros in the first row and column."""
    table = np.zeros((values.shape[0] + 1, values.shape[1] + 1), int)
    table[1:, 1:] = np.asarray(values, int).cumsum(0).cumsum(1)
    return table


def _refuses_many(xs: np.ndarray, ys: np.ndarray, values: np.ndarray, x: np.ndarray, y: np.ndarray,
                  margin: float, table: np.ndarray | None = None) -> np.ndarray:
    """:func:`_refuses_on` at every point of the arrays ``x``, ``y`` (a summed-area table counts the reached nodes
    of each point's window; ``table``: the layer's :func:`summed_area`, computed when not given)."""
    on = (xs[0] - 1e-9 <= x) & (x <= xs[-1] + 1e-9) & (ys[0] - 1e-9 <= y) & (y <= ys[-1] + 1e-9)
    i0 = np.maximum(0, np.searchsorted(xs, x - margin - 1e-9, side="right") - 1)
    i1 = np.minimum(len(xs) - 1, np.searchsorted(xs, x + margin + 1e-9, side="left"))
    j0 = np.maximum(0, np.searchsorted(ys, y - margin - 1e-9, side="right") - 1)
    j1 = np.minimum(len(ys) - 1, np.searchsorted(ys, y + margin + 1e-9, side="left"))
    if table is None:
        table = summed_area(values)
    reached = table[j1 + 1, i1 + 1] - table[j0, i1 + 1] - table[j1 + 1, i0] + table[j0, i0]
    return on & (reached == 0)


@dataclasses.dataclass(frozen=True)
class ReachMap:
    """``xs``, ``ys``: grid coordinates (S, m, increasing); ``reach[layer]``: bool (len(ys), len(xs)), True where
    the planner reached; ``heights``: the tool's height per layer (m); ``station``: the station file it is of;
    ``hold_ys`` and ``hold``: the optional hold layers' y grid and layers, bool (len(hold_ys), len(xs)) (empty
    when the map has none); ``approach_xs``, ``approach_ys`` and ``approach``: the optional pre-approach layers'
    grid and layers, bool (len(approach_ys), len(approach_xs))."""

    station: str
    xs: np.ndarray
    ys: np.ndarray
    reach: dict
    heights: dict
    hold_ys: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    hold: dict = dataclasses.field(default_factory=dict)
    approach_xs: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    approach_ys: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    approach: dict = dataclasses.field(default_factory=dict)
    _tables: dict = dataclasses.field(default_factory=dict, compare=False, repr=False)  # summed-area tables per layer

    def refuses(self, layer: str, x: float, y: float, margin: float = 0.0) -> bool:
        """True when every grid node around (x +- margin, y +- margin) is unreachable in ``layer`` (see the
        module docstring); False off the grid or where any such node was reached."""
        return _refuses_on(self.xs, self.ys, self.reach[layer], x, y, margin)

    def refuses_cup(self, x: float, y: float, z: float, yaw: float, margin: float = 0.0) -> bool:
        """A suction's cup at contact (x, y, z) with the tool turned ``yaw`` (rad): at yaw 0 the ``cup`` layer's
        verdict (at its one height, as the push layers); turned, True only when the map holds the layers of every
        yaw node and height node around (``yaw``, z) (one node where it is on one; the yaw-0 node is ``cup`` at
        its height) and each refuses (x, y); False beyond the nodes or where a layer is missing."""
        deg = math.degrees(yaw)
        if abs(deg) < 1e-9:
            return self.refuses("cup", x, y, margin)
        yaws, heights = sorted((0,) + TURNED_CUP_YAWS_DEG), TURNED_CUP_HEIGHTS
        if not (yaws[0] - 1e-9 <= deg <= yaws[-1] + 1e-9 and heights[0] - 1e-9 <= z <= heights[-1] + 1e-9):
            return False
        around_yaw = {max(n for n in yaws if n <= deg + 1e-9), min(n for n in yaws if n >= deg - 1e-9)}
        around_z = {max(h for h in heights if h <= z + 1e-9), min(h for h in heights if h >= z - 1e-9)}
        for d in around_yaw:
            for h in around_z:
                if d == 0:
                    if abs(self.heights.get("cup", math.nan) - h) > 1e-9:
                        return False
                    layer = "cup"
                else:
                    layer = turned_cup_layer(d, h)
                if layer not in self.reach or not self.refuses(layer, x, y, margin):
                    return False
        return True

    def refuses_release(self, x: float, y: float, margin: float = 0.0) -> bool:
        """A yaw-0 suction releasing its object with the cup's contact at (x, y) (S, m): True when the map holds
        the release layers and the back-off or the retract layer refuses (x, y); False when it has none."""
        return any(layer in self.reach and self.refuses(layer, x, y, margin) for layer in RELEASE_LAYERS)

    def hold_refusals(self, x, y, yaw: float, margin: float = 0.0, family: str = "hold") -> np.ndarray:
        """Per point of ``x``, ``y`` (S, m; arrays of one shape, or scalars) and height node of
        :data:`HOLD_HEIGHTS` (the last axis): whether the hold layer (``family`` "approach": the pre-approach
        layer) of every yaw node around ``yaw`` (rad; one node where it is on one) at that height exists and
        refuses the cup tip there. All False when the map has no such layers, beyond the yaw nodes, and off the
        grid."""
        layers, xs, ys = ((self.hold, self.xs, self.hold_ys) if family == "hold"
                          else (self.approach, self.approach_xs, self.approach_ys))
        x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        out = np.zeros(x.shape + (len(HOLD_HEIGHTS),), bool)
        deg = math.degrees(yaw)
        yaws = family_yaws_deg(family)
        if not layers or not yaws[0] - 1e-9 <= deg <= yaws[-1] + 1e-9:
            return out
        around_yaw = {max(n for n in yaws if n <= deg + 1e-9), min(n for n in yaws if n >= deg - 1e-9)}
        for k, h in enumerate(HOLD_HEIGHTS):
            refused = np.ones(x.shape, bool)
            for d in around_yaw:
                name = hold_layer(d, h, family)
                values = layers.get(name)
                if values is None:
                    refused &= False
                    continue
                table = self._tables.get(name)
                if table is None:
                    table = self._tables[name] = summed_area(values)
                refused &= _refuses_many(xs, ys, values, x, y, margin, table)
            out[..., k] = refused
        return out

    def refuses_approach(self, x: float, y: float, z: float, yaw: float, margin: float = 0.0) -> bool:
        """A suction's pre-approach, the cup tip at (x, y, z) (S, m) with the tool turned ``yaw`` (rad) and suction
        off: True only when the pre-approach layers of every yaw node and height node around it exist and refuse
        it (:meth:`hold_refusals` with ``family`` "approach")."""
        span = hold_height_span(z, z)
        return span is not None and bool(
            self.hold_refusals(x, y, yaw, margin, "approach")[..., span[0]:span[1] + 1].all())

    def refuses_hold(self, x: float, y: float, z_lo: float, z_hi: float, yaw: float, margin: float = 0.0) -> bool:
        """The cup tip holding an object at (x, y) (S, m), somewhere between heights ``z_lo`` and ``z_hi`` (m above
        the support), the tool turned ``yaw`` (rad) about S z: True only when the map holds the hold layers of every
        yaw node around ``yaw`` and every height node from the one at or below ``z_lo`` to the one at or above
        ``z_hi`` (:func:`hold_height_span`), and each refuses (x, y); False beyond the nodes, off the grid or where
        a layer is missing."""
        span = hold_height_span(z_lo, z_hi)
        return span is not None and bool(self.hold_refusals(x, y, yaw, margin)[..., span[0]:span[1] + 1].all())

    def to_dict(self) -> dict:
        data = {"station": self.station, "xs": [round(float(v), 6) for v in self.xs],
                "ys": [round(float(v), 6) for v in self.ys], "heights": dict(self.heights),
                "reach": {k: np.asarray(v, int).tolist() for k, v in self.reach.items()}}
        if self.hold:
            data["hold_ys"] = [round(float(v), 6) for v in self.hold_ys]
            data["hold"] = {k: np.asarray(v, int).tolist() for k, v in self.hold.items()}
        if self.approach:
            data["approach_xs"] = [round(float(v), 6) for v in self.approach_xs]
            data["approach_ys"] = [round(float(v), 6) for v in self.approach_ys]
            data["approach"] = {k: np.asarray(v, int).tolist() for k, v in self.approach.items()}
        return data

    @staticmethod
    def from_dict(data: dict) -> "ReachMap":
        return ReachMap(data["station"], np.array(data["xs"], float), np.array(data["ys"], float),
                        {k: np.array(v, bool) for k, v in data["reach"].items()}, dict(data["heights"]),
                        np.array(data.get("hold_ys", []), float),
                        {k: np.array(v, bool) for k, v in data.get("hold", {}).items()},
                        np.array(data.get("approach_xs", []), float), np.array(data.get("approach_ys", []), float),
                        {k: np.array(v, bool) for k, v in data.get("approach", {}).items()})


def reach_map_file(path: str) -> Path:
    """The file a reach map path names: as given when it exists, else relative to the repository root."""
    from slax_drake.config import REPO_ROOT

    p = Path(path)
    return p if p.is_absolute() or p.is_file() else REPO_ROOT / p


@functools.lru_cache(maxsize=8)
def load_reach_map(path: str) -> ReachMap:
    """The reach map JSON at ``path`` (relative paths from the repository root), read once per process."""
    from slax_drake.errors import ConfigError

    p = reach_map_file(path)
    try:
        data = json.loads(p.read_text())
        rmap = ReachMap.from_dict(data)
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise ConfigError(f"{path}: not a reach map ({e})") from None
    for layer in LAYERS:
        if layer not in rmap.reach:
            raise ConfigError(f"{path}: reach map without a {len(rmap.ys)} x {len(rmap.xs)} layer {layer!r}")
    for layer, values in rmap.reach.items():  # the turned-cup layers too
        if values.shape != (len(rmap.ys), len(rmap.xs)):
            raise ConfigError(f"{path}: reach map layer {layer!r} is {' x '.join(map(str, values.shape))}, not "
                              f"{len(rmap.ys)} x {len(rmap.xs)}")
    for layer, values in rmap.hold.items():
        if values.shape != (len(rmap.hold_ys), len(rmap.xs)):
            raise ConfigError(f"{path}: reach map hold layer {layer!r} is {' x '.join(map(str, values.shape))}, not "
                              f"{len(rmap.hold_ys)} x {len(rmap.xs)}")
    for layer, values in rmap.approach.items():
        if values.shape != (len(rmap.approach_ys), len(rmap.approach_xs)):
            raise ConfigError(f"{path}: reach map pre-approach layer {layer!r} is {' x '.join(map(str, values.shape))}, "
                              f"not {len(rmap.approach_ys)} x {len(rmap.approach_xs)}")
    return rmap


def grid(lo: float, hi: float, step: float) -> np.ndarray:
    """Grid coordinates from ``lo`` to ``hi`` (inclusive, ``step`` apart, the last one at ``hi``)."""
    n = int(math.floor((hi - lo) / step + 1e-9))
    values = lo + step * np.arange(n + 1)
    return values if abs(values[-1] - hi) < 1e-9 else np.append(values, hi)
