"""Where the Meshcat view (live, and the HTML replay recorded from it) looks when it opens: into the shelf bay
over the robot's shoulder, so that the objects, the target and the tool are in view.

Meshcat's own default camera sits a few metres out along the world's x and y axes, which here is behind and
beside the shelf: the first view is of the outside of the bay. The pose below is given in the shelf frame S
(x to the right as seen from the robot's camera, y into the shelf, z up; origin at the centre of the support
surface) and moved to the world with X_WS, so it follows the shelf wherever the station puts it.
"""

from __future__ import annotations

import numpy as np

# The viewpoint, in metres of S, relative to the bay: behind the tool camera (which looks in from 0.75 m in front
# of the shelf's centre), a little to its right and above the top of the bay, where the robot's shoulder is; the
# point looked at is just above the support surface, a third of the way into the bay. The tool in front of the
# opening stays in the lower part of the picture and the whole bay above it (checked by a headless-Chromium
# screenshot, tests/systems/test_trial_view.py).
EYE_BEHIND_FRONT = 0.85  # m in front of the bay's open face (-y)
EYE_RIGHT = 0.25  # m along +x
EYE_ABOVE_TOP = 0.25  # m above the bay's top panel
LOOK_INTO = 1.0 / 3.0  # the point looked at: this fraction of the bay's depth behind its open face
LOOK_HEIGHT = 0.08  # m above the support surface


def replay_camera_in_shelf(shelf) -> tuple[np.ndarray, np.ndarray]:
    """(eye, target) positions in the shelf frame S (metres) for a shelf with ``width``, ``depth`` and
    ``height``."""
    front = -shelf.depth / 2.0
    eye = np.array([EYE_RIGHT, front - EYE_BEHIND_FRONT, shelf.height + EYE_ABOVE_TOP])
    target = np.array([0.0, front + LOOK_INTO * shelf.depth, LOOK_HEIGHT])
    return eye, target


def set_replay_camera(meshcat, X_WS, shelf) -> None:
    """Points ``meshcat``'s default camera into the bay of ``shelf`` (placed at ``X_WS``, a RigidTransform) over
    the robot's shoulder. Call it before ``StaticHtml()``: the HTML replay opens with the camera it has then."""
    eye_S, target_S = replay_camera_in_shelf(shelf)
    meshcat.SetCameraPose(X_WS.multiply(eye_S), X_WS.multiply(target_S))
