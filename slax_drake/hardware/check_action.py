"""Checking one action's kinematic feasibility on a scene, as a user-facing tool (``slax-drake check-action``).

An action is named ``push:OBJECT:D`` (the blade pushes OBJECT by D metres along the shelf's x, signed) or
``suction:OBJECT:DX:DZ`` (the cup picks OBJECT, moves it DX along x and places its centre at depth y = DZ; m, shelf
frame S). :func:`check_action` asks first the action model (the station's rules: the ``station`` profile with the
station cup's limits, the same as a Drake trial's) whether the action exists on the scene as it stands, then the
motion planner whether the arm can execute it (IK, collision checks, Ruckig timing). It returns an
:class:`ActionCheck`: feasible or the first reason it is not, the motion's duration and the planner's IK / check /
Ruckig times. :func:`check_all` does so for every candidate the action model lists for the scene (and reports the
candidates it refuses with the model's reason); :func:`verdict_png` draws them top-down, coloured by verdict.

The action model and the planner see the scene's objects as known, not its target (the robot does not know where
the target is). A push's blade lane and a suction's contact (and the tool's yaw) are the action model's for that
object; a push distance need not lie on the model's lattice, but must not exceed the longest push the model
admits in that direction.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from slax_drake.errors import ActionSpecError

PUSH_TOLERANCE = 1e-6  # m: a push distance this far beyond the model's longest is still that push
SUCTION_TOLERANCE = 5e-4  # m: a suction's dx/dz this close to a candidate's (0.05 m apart) is that candidate


@dataclasses.dataclass
class ActionCheck:
    """The verdict on one action: ``stage`` "ok", "action model" (the model refuses it) or "motion" (the planner
    finds no motion); ``reason`` the first reason it is infeasible; ``duration_s`` the motion's length and
    ``timings`` the planner's seconds (ik_s, check_s, timing_s, total_s) when it was planned."""

    action: str
    feasible: bool
    stage: str
    reason: str = ""
    duration_s: float | None = None
    timings: dict = dataclasses.field(default_factory=dict)
    planned: object = None  # the Push or Suction checked (None when the action model knows no such action)
    object_name: str = ""  # the object of a candidate the action model refuses
    kind: str = ""  # the typed reason: the action model's RefusalKind value or the planner's FailureKind value

    def line(self) -> str:
        if self.feasible:
            t = self.timings
            return (f"{self.action}: feasible, motion {self.duration_s:.2f} s; planning {t.get('total_s', 0):.3f} s "
                    f"(IK {t.get('ik_s', 0):.3f} s, checks {t.get('check_s', 0):.3f} s, Ruckig {t.get('timing_s', 0):.3f} s)")
        times = f" (planning {self.timings['total_s']:.3f} s)" if self.timings.get("total_s") is not None else ""
        return f"{self.action}: infeasible ({self.stage}): {self.reason}{times}"


def parse_action(text: str) -> tuple:
    """``push:NAME:D`` -> ("push", NAME, D); ``suction:NAME:DX:DZ`` -> ("suction", NAME, DX, DZ)."""
    parts = text.split(":")
    try:
        if parts[0] == "push" and len(parts) == 3 and parts[1]:
            spec = "push", parts[1], float(parts[2])
        elif parts[0] == "suction" and len(parts) == 4 and parts[1]:
            spec = "suction", parts[1], float(parts[2]), float(parts[3])
        else:
            spec = None
    except ValueError:
        spec = None
    if spec is not None:
        if not all(math.isfinite(v) for v in spec[2:]):
            raise ActionSpecError(f"--action {text!r}: distances must be finite numbers in metres")
        return spec
    raise ActionSpecError(f"--action {text!r}: expected push:OBJECT:D or suction:OBJECT:DX:DZ (metres, e.g. "
                          "push:object_5:-0.10)")


@dataclasses.dataclass
class Checker:
    """The action model and the motion planner of one station for one scene (built by :func:`make_checker`)."""

    scene: object
    model: object
    planner: object
    station_path: str

    def candidates(self):
        return self.model.enumerate(self.scene.objects)

    def resolve(self, spec: tuple, candidates=None):
        """The action model's Push or Suction for ``spec`` (:func:`parse_action`), or (None, why not)."""
        from slax_drake.shelf.actions import Push

        kind, name = spec[0], spec[1]
        if name not in {o.name for o in self.scene.objects}:
            raise ActionSpecError(f"no object named {name!r} in the scene (objects: "
                                  f"{', '.join(o.name for o in self.scene.objects)})")
        cands = candidates or self.model.enumerate(self.scene.objects, only={name})
        if kind == "push":
            d = spec[2]
            if d == 0.0:
                raise ActionSpecError("a push needs a non-zero distance D")
            same = [a for a in cands.feasible if isinstance(a, Push) and a.name == name and (a.d > 0) == (d > 0)]
            if not same:
                why = [r.reason for r in cands.rejected if r.action_kind == "push" and r.object_name == name
                       and r.direction == (1 if d > 0 else -1)]
                return None, (why[0] if why else f"the action model lists no push of {name} toward "
                              f"{'+' if d > 0 else '-'}x")
            longest = max(abs(a.d) for a in same)
            if abs(d) > longest + PUSH_TOLERANCE:
                return None, f"{name} can be pushed at most {longest:.3f} m toward {'+' if d > 0 else '-'}x here"
            return dataclasses.replace(same[0], d=d), ""
        dx, dz = spec[2], spec[3]
        mine = [a for a in cands.feasible if a.kind == "suction" and a.name == name]
        match = [a for a in mine if abs(a.dx - dx) <= SUCTION_TOLERANCE and abs(a.dz - dz) <= SUCTION_TOLERANCE]
        if match:
            return match[0], ""
        if mine:
            return None, (f"no suction of {name} places it at dx = {dx:+.3f}, y = {dz:+.3f} (its {len(mine)} "
                          "placements are on the model's lattice, e.g. " +
                          ", ".join(f"{a.dx:+.3f}:{a.dz:+.3f}" for a in mine[:3]) + ")")
        why = [r.reason for r in cands.rejected if r.action_kind == "suction" and r.object_name == name]
        return None, why[0] if why else f"the action model lists no suction of {name}"

    def check(self, spec: tuple, text: str, candidates=None) -> ActionCheck:
        action, why = self.resolve(spec, candidates)
        if action is None:
            return ActionCheck(text, False, "action model", why)
        return self.plan(action, text)

    def plan(self, action, text: str | None = None) -> ActionCheck:
        result = self.planner.plan(action, self.scene)
        text = text or spec_of(action)
        timings = {k: result.timings[k] for k in ("ik_s", "check_s", "timing_s", "total_s") if k in result.timings}
        if not result.feasible:
            kind = result.failure.kind.value if result.failure is not None else ""
            return ActionCheck(text, False, "motion", result.reason, None, timings, action, kind=kind)
        return ActionCheck(text, True, "ok", "", round(float(result.trajectory.duration), 3), timings, action)


def spec_of(action) -> str:
    """The ``--action`` text of a Push or Suction."""
    if action.kind == "push":
        return f"push:{action.name}:{action.d:+.4f}"
    return f"suction:{action.name}:{action.dx:+.4f}:{action.dz:+.4f}"


def make_checker(scene, station_path: str | None = None, tool=None, tool_rules: dict | None = None) -> Checker:
    """The station's action model (``station`` profile, the station cup's limits with ``tool_rules`` on top, the
    station's scene scenario's geometry and masses; ``tool``, a ToolConfig, instead when given) and motion planner
    for ``scene``."""
    from slax_drake.config import load_scenario
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.shelf.actions import ActionModel
    from slax_drake.shelf.tool import tool_config
    from slax_drake.station.plant import scene_camera
    from slax_drake.station.scenario import load_station_scenario, station_for
    from slax_drake.systems.trial import station_tool_rules

    station_path = station_path or station_for(shelf=scene.shelf)
    station = load_station_scenario(station_path)
    scene_camera(station, scene)  # SceneMismatchError when the station serves another shelf
    if tool is None:
        tool = tool_config(load_scenario(station.scene_config), "station", **station_tool_rules(station, tool_rules))
    model = ActionModel(scene.shelf, scene.camera.position[:2], tool)
    known = dataclasses.replace(scene, target=None)
    return Checker(known, model, MotionPlanner(station, tool), str(station_path))


def _scene(scene):
    """A Scene, or the scene JSON at that path."""
    from slax_drake.scene.io import load_scene

    return load_scene(scene) if isinstance(scene, (str, Path)) else scene


def check_action(scene, action: str, station: str | None = None, tool_rules: dict | None = None) -> ActionCheck:
    """The verdict on ``action`` (``push:OBJECT:D`` or ``suction:OBJECT:DX:DZ``) on ``scene`` (a Scene or the path
    of a scene JSON) with ``station`` (default: the shipped station with the scene's shelf,
    :func:`slax_drake.station.scenario.station_for`) and ``tool_rules`` over the station's."""
    spec = parse_action(action)
    checker = make_checker(_scene(scene), station, tool_rules=tool_rules)
    return checker.check(spec, action)


def check_all(scene, station: str | None = None, progress: bool | None = False,
              tool_rules: dict | None = None) -> tuple[Checker, list[ActionCheck]]:
    """Every candidate action of ``scene`` (a Scene or the path of a scene JSON) with its verdict: the action
    model's feasible candidates planned in its order, then one line per candidate (group) it refuses, with its
    reason. ``progress``: a progress bar of the candidates planned on stderr (None: when stderr is a terminal);
    ``tool_rules``: over the station's."""
    from tqdm import tqdm

    checker = make_checker(_scene(scene), station, tool_rules=tool_rules)
    cands = checker.candidates()
    checks = [checker.plan(a) for a in tqdm(cands.feasible, desc="planning candidates", unit="candidate",
                                            disable=None if progress is None else not progress, leave=False)]
    checks += [ActionCheck(r.spec(), False, "action model", r.reason, object_name=r.object_name,
                           kind=r.kind.value if r.kind is not None else "")
               for r in cands.rejected]
    return checker, checks


def table(checks: list[ActionCheck]) -> str:
    """A plain-text table: action, verdict, the reason's kind (typed), motion duration, planning times, reason."""
    rows = [("action", "verdict", "kind", "motion s", "plan s", "IK s", "check s", "Ruckig s", "reason")]
    for c in checks:
        t = c.timings

        def s(key):
            return f"{t[key]:.3f}" if key in t else "-"

        rows.append((c.action, "feasible" if c.feasible else f"no ({c.stage})", c.kind or "-",
                     "-" if c.duration_s is None else f"{c.duration_s:.2f}", s("total_s"), s("ik_s"), s("check_s"),
                     s("timing_s"), c.reason[:90]))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]) - 1)]
    lines = ["  ".join(v.ljust(w) for v, w in zip(r[:-1], widths)) + "  " + r[-1] for r in rows]
    feasible = sum(c.feasible for c in checks)
    motion = sum(c.stage == "motion" for c in checks)
    model = sum(c.stage == "action model" for c in checks)
    from slax_drake.io import plural

    return "\n".join(lines + [f"{plural(len(checks), 'candidate')}: {feasible} feasible, {motion} without a motion, {model} "
                              "refused by the action model"]) + "\n"


VERDICT_COLOURS = {"ok": "#2ca02c", "motion": "#d62728", "action model": "#7f7f7f"}


def verdict_png(checker: Checker, checks: list[ActionCheck]) -> bytes:
    """Top-down view of the shelf (S x right, y into the shelf, the opening at the bottom): the objects' footprints
    and, per planned candidate, an arrow from the object's centre to where the action model moves it, green when
    a motion was found, red when not; objects with a candidate the model refuses are outlined in grey."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon, Rectangle

    from slax_drake.io import figure_png
    from slax_drake.scene.footprint import Footprint

    scene = checker.scene
    shelf = scene.shelf
    fig, ax = plt.subplots(figsize=(7, 7 * shelf.depth / shelf.width + 0.8))
    ax.add_patch(Rectangle((-shelf.width / 2, -shelf.depth / 2), shelf.width, shelf.depth, fill=False, lw=1.5))
    refused = {c.object_name for c in checks if c.stage == "action model"}
    centres = {}
    for o in scene.objects:
        fp = Footprint.of(o)
        if o.shape == "cylinder":
            from matplotlib.patches import Circle

            patch = Circle((fp.x, fp.y), fp.half_x)
        else:
            patch = Polygon(fp.corners(), closed=True)
        patch.set_facecolor("#c6dbef")
        patch.set_edgecolor("#7f7f7f" if o.name in refused else "#1f77b4")
        patch.set_linewidth(2.0 if o.name in refused else 1.0)
        ax.add_patch(patch)
        ax.annotate(o.name.replace("object_", ""), (fp.x, fp.y), ha="center", va="center", fontsize=8)
        centres[o.name] = (fp.x, fp.y)
    for c in checks:
        a = c.planned
        if a is None:
            continue
        x, y = centres[a.name]
        dx, dy = (a.d, 0.0) if a.kind == "push" else (a.dx, a.dz - y)
        ax.annotate("", (x + dx, y + dy), (x, y), arrowprops=dict(arrowstyle="->", color=VERDICT_COLOURS[c.stage],
                                                                  lw=1.2, alpha=0.7, shrinkA=0, shrinkB=0))
    for stage, label in (("ok", "motion found"), ("motion", "no motion"), ("action model", "refused by the model")):
        n = sum(c.stage == stage for c in checks)
        ax.plot([], [], color=VERDICT_COLOURS[stage], label=f"{label} ({n})")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_xlim(-shelf.width / 2 - 0.02, shelf.width / 2 + 0.02)
    ax.set_ylim(-shelf.depth / 2 - 0.02, shelf.depth / 2 + 0.02)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m), shelf frame")
    ax.set_ylabel("y (m), into the shelf")
    ax.set_title(f"every candidate action, by verdict ({Path(checker.station_path).name})", fontsize=10)
    fig.tight_layout()
    return figure_png(fig, 110)
