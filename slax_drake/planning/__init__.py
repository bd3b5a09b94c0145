"""Motion planning for the bluction tool: tool waypoints of an action, IK, collision checks, Ruckig timing.

Data flow: a policy's action (``slax_drake.shelf.actions``) -> Cartesian tool waypoints in the shelf frame
(:mod:`waypoints`) -> joint waypoints by Drake's InverseKinematics, warm-started along the path (:mod:`ik`) ->
straight segments in joint space, refined until the tool deviates < 5 mm from its Cartesian segment and checked
densely with Drake's SceneGraphCollisionChecker against the world as it stands (:mod:`world`) -> timed segment by
segment with Ruckig (:mod:`timing`) -> a :class:`~slax_drake.planning.trajectory.JointTrajectory`.
:class:`~slax_drake.planning.planner.MotionPlanner` runs the chain and returns a motion or a rejection.
"""

from slax_drake.planning.trajectory import JointTrajectory

__all__ = ["JointTrajectory"]
