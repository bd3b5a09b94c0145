"""A scene object's pose cannot change in place (the action model's caches key footprints by object identity)."""

import numpy as np
import pytest

from slax_drake.scene.model import SceneObject


def test_an_objects_pose_is_read_only_and_moving_makes_a_new_object():
    X = np.eye(4)
    obj = SceneObject(name="object_0", shape="box", size=(0.1, 0.1, 0.2), X_SO=X)
    X[0, 3] = 5.0  # the caller's array is not the object's
    assert obj.center[0] == 0.0
    with pytest.raises(ValueError):
        obj.X_SO[0, 3] = 1.0
    moved = obj.moved_to(0.2, -0.1)
    assert moved is not obj and tuple(moved.center[:2]) == (0.2, -0.1) and obj.center[0] == 0.0
    assert not moved.X_SO.flags.writeable
    assert SceneObject(name="t", shape="box", size=(0.1, 0.1, 0.1), X_SO=X.tolist()).X_SO.dtype == np.float64
