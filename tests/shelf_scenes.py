"""Hand-built scene pieces shared by the policy tests: the Table I target size and an axis-aligned box."""

from slax_drake.scene.model import SceneObject, planar_pose

TARGET = (0.06, 0.06, 0.06)  # the Table I target, a 0.06 m cube


def box(name, x, y, sx, sy, sz):
    """A box of size (sx, sy, sz) m standing on the shelf at (x, y) in the shelf frame S, square to the walls."""
    return SceneObject(name, "box", (sx, sy, sz), planar_pose(x, y, sz / 2, 0.0))
