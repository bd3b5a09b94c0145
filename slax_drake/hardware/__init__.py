"""Running trajectories on a real Fetch: export formats, an independent limit and collision checker, replay.

- :mod:`~slax_drake.hardware.trajectory_file`: the exported trajectory (one ROS JointTrajectory-shaped message per
  motion plus timed suction events) and its three file formats (ROS-JSON, ROS-YAML FollowJointTrajectory goals,
  CSV), with strict loading (``TrajectoryFileError``).
- :mod:`~slax_drake.hardware.export`: a trial's ``trial.json`` -> exported trajectory (optionally resampled).
- :mod:`~slax_drake.hardware.rosbag_export`: a whole trial as a ROS 2 bag with MCAP storage (joint states, planned
  trajectories, suction command, TF of the shelf and objects, depth images), written with ``rosbags``.
- :mod:`~slax_drake.hardware.interpolation`: quintic Hermite interpolation of (q, v, a) samples.
- :mod:`~slax_drake.hardware.fetch_limits`: the real Fetch's joint limits, typed in from the robot's published
  description (independent of our model file and of the planner).
- :mod:`~slax_drake.hardware.check`: the checker (limits, jerk, continuity, collisions).
- :mod:`~slax_drake.hardware.replay`: plays an exported trajectory open loop in the Drake station.
"""
