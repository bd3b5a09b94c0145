"""One line per decision of a running Drake trial, printed as it happens (``slax-drake trial`` writes them on stderr).

A line starts when the planner has chosen and planned an action and ends when the next decision (or the end of the
trial) shows where the object went::

    step 3/12: push track_2 -0.100 m (its plan reveals 61% of the belief), planned in 0.4 s after 1 rejected candidate, executed, object_4 moved as predicted
    step 4/12: suction track_1 by +0.050 m to y = -0.190 m, planned in 1.2 s, executed, object_1 ended 3.4 cm from the prediction
    step 5/12: suction track_3 by -0.100 m to y = +0.150 m, planned in 0.9 s, guarded, stopped on contact after 0.212 m, executed, object_2 ended 6.1 cm from the prediction
    step 6/12: suction track_4 by -0.050 m to y = -0.220 m, planned in 0.7 s, weighed 7.8 N hanging 0.37 N m off the cup, not hanging free: put back
    step 7/12: suction track_0 by -0.200 m to y = -0.050 m, planned in 0.3 s, weighed along the pull: 7.9 N of friction, a twist of 0.72 N m across > 0.64, twists off the cup: pushed back
    done after 4 actions: target revealed (96% of it visible)

What a line says is what the trial knows at that moment: the policy's action on a camera segment, for a policy that
keeps a decision log the share of its belief the plan it took reveals (or that no plan reveals anything), the planner's
seconds, and the referee's view of the outcome (the true object behind the segment, its pose at the next decision
against the action model's prediction, within the physics benchmark's tolerances: 2 cm and 10 deg; lost when it
toppled or left the bay). A segment that no true object stood behind has no judged outcome ("executed").
"""

from __future__ import annotations

import sys

from slax_drake.io import plural


def _plan_text(entry: dict) -> str:
    """For a policy that keeps a decision log (slax-belief): how much of its belief the plan it took reveals, or that
    its search found no plan revealing anything (it stalled, and moves on); empty for the others."""
    from slax_drake.evaluation.physics import is_stall

    logs = entry.get("decision_log") or []
    last = logs[-1] if logs else {}
    if "revealed" not in last:
        return ""
    if is_stall(last):
        return " (no plan reveals any place the target may stand: moving on)"
    return f" (its plan reveals {100 * float(last['revealed']):.0f}% of the belief)"


class DecisionPrinter:
    """Feeds on the planner's decision log and the evaluator's snapshots while the simulation advances
    (:meth:`update`) and writes each decision's line to ``stream`` (default: stderr); :meth:`finish` closes the last
    one with the final object poses. ``horizon``: the trial's H, for "step N/H"."""

    def __init__(self, horizon: int, stream=None):
        self.horizon = horizon
        self.stream = stream if stream is not None else sys.stderr
        self.seen = 0  # log entries handled
        self.open = None  # (entry, snapshot) of the action whose line awaits its outcome

    def _write(self, text: str) -> None:
        self.stream.write(text)
        self.stream.flush()

    def update(self, log, snapshots) -> None:
        """Handles the log entries that arrived since the last call; ``snapshots``: the evaluator's so far."""
        if self.open is not None:  # the open action's entry as it stands now (a guarded push-in adds its record)
            step = self.open[0]["step"]
            latest = next((e for e in log if e.get("step") == step and "action" in e), None)
            if latest is not None:
                self.open = (latest, self.open[1])
        for entry in log[self.seen:]:
            snap = _snapshot_at(snapshots, entry["time"])
            if self.open is not None:
                self._close(snap.poses if snap else None, snap.lost if snap else ())
            if "action" in entry:
                self._write(self._decision_text(entry))
                self.open = (entry, snap)
            elif entry.get("final"):
                self._write(self._final_text(entry, snap))
        self.seen = len(log)

    def finish(self, final_objects: dict | None) -> None:
        """Closes a line still waiting for its outcome (the trial stopped during its motion), judged from
        ``final_objects`` ({name: {"x", "y", "yaw", "upright", "inside"}}, shelf frame, m and rad)."""
        if self.open is None:
            return
        if final_objects is None:
            self._close(None, ())
            return
        poses = {n: (p["x"], p["y"], p["yaw"]) for n, p in final_objects.items()}
        lost = tuple(n for n, p in final_objects.items() if not (p["upright"] and p["inside"]))
        self._close(poses, lost)

    # ---------------------------------------------------------------------------------------------------------
    def _decision_text(self, entry: dict) -> str:
        a = entry["action"]
        if a["type"] == "push":
            what = f"push {a['object']} {a['d']:+.3f} m"
        else:
            grip = " (dragged)" if a.get("grip") == "drag" else ""
            what = f"suction {a['object']} by {a['dx']:+.3f} m to y = {a['dz']:+.3f} m{grip}"
        rejected = len(entry.get("rejected", ()))
        return (f"step {entry['step'] + 1}/{self.horizon}: {what}{_plan_text(entry)}, planned in "
                f"{entry.get('planning_s', 0.0):.1f} s"
                + (f" after {plural(rejected, 'rejected candidate')}" if rejected else "") + ", ")

    def _final_text(self, entry: dict, snap) -> str:
        from slax_drake.systems.trial_summary import OUTCOMES

        result = entry.get("result", "?")
        text = OUTCOMES.get(result, "target not revealed: {result}").format(horizon=self.horizon, result=result)
        visible = f" ({snap.visible_fraction * 100:.0f}% of it visible)" if snap is not None else ""
        rejected = len(entry.get("rejected", ()))
        tried = f"; {plural(rejected, 'candidate')} without a motion" if rejected else ""
        reasons = entry.get("reasons")
        if reasons:  # the most frequent reason no candidate was executed (see the summary for the rest)
            top = reasons[0]
            tried += f"; most often {top['stage']}: {top['kind']} ({plural(top['count'], 'candidate')})"
        return f"done after {plural(entry['step'], 'action')}: {text}{visible}{tried}\n"

    def _close(self, poses: dict | None, lost) -> None:
        from slax_drake.evaluation.physics import action_matches
        from slax_drake.systems.drag_weigh import is_pull_record
        from slax_drake.systems.guard import dragged_after_weighing

        entry, snap = self.open
        self.open = None
        weighed = entry.get("weighed")
        if is_pull_record(weighed) and weighed.get("put_back"):  # a drag weighed along its pull
            self._write(f"weighed along the pull: {weighed['friction_n']:.1f} N of friction, a twist of "
                        f"{weighed['twist_nm']:.2f} N m across > {weighed['limit_nm']:.2f}, {weighed['why']}: "
                        "pushed back\n")
            return
        if weighed and weighed.get("put_back"):  # weighed at the lift: undone, and then dragged or nothing more
            self._write(f"weighed {weighed['weight_n']:.1f} N hanging {weighed['moment_nm']:.2f} N m off the cup, "
                        f"{weighed['why']}: put back")
            if not dragged_after_weighing(entry):
                self._write("\n")
                return
            self._write(", dragged instead, ")
        guard = entry.get("guarded")
        if guard:
            edge = guard.get("edge_stop")
            retried = (f"stopped at the board's front edge after {edge.get('pushed_in_m', 0.0):.3f} m and pushed in "
                       "again higher, " if edge else "")
            if guard.get("edge_only"):  # an unguarded lift's push-in, watched at the edge only
                self._write(retried)
            else:
                self._write("guarded, " + retried + (f"stopped on contact after {guard.get('pushed_in_m', 0.0):.3f} m, "
                                                     if guard["stopped"] else "completed, "))
        segment = entry.get("segment_of", {}).get(entry["action"]["object"], entry["action"]["object"])
        true_object = snap.segments.get(segment) if snap is not None else None
        if true_object is None or poses is None or true_object not in poses or true_object not in snap.poses:
            self._write("executed\n")
            return
        if true_object in lost:
            self._write(f"executed, {true_object} was lost (toppled or off the shelf)\n")
            return
        x, y, yaw = poses[true_object]
        bx, by, byaw = snap.poses[true_object]
        predicted = entry["predicted_objects"]
        matched = action_matches(predicted, {"x": x, "y": y, "yaw": yaw}, {"x": bx, "y": by, "yaw": byaw})
        if matched:
            self._write(f"executed, {true_object} moved as predicted\n")
        else:
            off = ((x - predicted["x"]) ** 2 + (y - predicted["y"]) ** 2) ** 0.5
            self._write(f"executed, {true_object} ended {off * 100:.1f} cm from the prediction\n")


def _snapshot_at(snapshots, time: float):
    return next((s for s in snapshots if abs(s.time - time) < 5e-4), None)
