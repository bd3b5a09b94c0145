"""The one camera model of slax-drake: pinhole intrinsics and the pose X_SC in the shelf frame.

Camera frame C (Drake's and OpenCV's convention): origin at the optical centre, z along the optical axis,
x to the right in the image, y down in the image. Pixel (u, v) has its centre at integer coordinates;
u = fx * x / z + cx, v = fy * y / z + cy. The occupancy projection, the dataset renderer and the
RgbdSensor of the Drake diagram all build from this class, so they agree pixel for pixel.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from slax_drake.config import ShelfCameraConfig


@dataclasses.dataclass(frozen=True)
class Camera:
    """Intrinsics (pixels) and the pose of the camera frame in the shelf frame (4x4, metres)."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    X_SC: np.ndarray
    near: float = 0.1
    far: float = 5.0

    @staticmethod
    def from_config(config: ShelfCameraConfig) -> "Camera":
        fx = (config.width / 2.0) / math.tan(math.radians(config.horizontal_fov_deg) / 2.0)
        return Camera(
            width=int(config.width),
            height=int(config.height),
            fx=fx,
            fy=fx,
            cx=(config.width - 1) / 2.0,
            cy=(config.height - 1) / 2.0,
            X_SC=camera_pose(config.position, config.pitch_deg),
            near=config.near,
            far=config.far,
        )

    @property
    def position(self) -> np.ndarray:
        """Optical centre in the shelf frame (metres)."""
        return self.X_SC[:3, 3]

    @property
    def vertical_fov(self) -> float:
        """Vertical field of view (radians)."""
        return 2.0 * math.atan(self.height / 2.0 / self.fy)

    @property
    def horizontal_fov(self) -> float:
        """Horizontal field of view (radians)."""
        return 2.0 * math.atan(self.width / 2.0 / self.fx)

    def with_resolution(self, width: int, height: int) -> "Camera":
        """The same camera (same fields of view and pose) imaged at another resolution."""
        sx, sy = width / self.width, height / self.height
        return dataclasses.replace(
            self,
            width=width,
            height=height,
            fx=self.fx * sx,
            fy=self.fy * sy,
            cx=(self.cx + 0.5) * sx - 0.5,
            cy=(self.cy + 0.5) * sy - 0.5,
        )

    def project(self, p_S: np.ndarray) -> np.ndarray:
        """Projects points (..., 3) in the shelf frame to pixel coordinates (..., 2) as (u, v)."""
        p_C = self.to_camera(p_S)
        z = p_C[..., 2]
        return np.stack([self.fx * p_C[..., 0] / z + self.cx, self.fy * p_C[..., 1] / z + self.cy], axis=-1)

    def to_camera(self, p_S: np.ndarray) -> np.ndarray:
        """Expresses points (..., 3) of the shelf frame in the camera frame."""
        R, t = self.X_SC[:3, :3], self.X_SC[:3, 3]
        return (np.asarray(p_S, dtype=float) - t) @ R

    def pixel_rays(self) -> np.ndarray:
        """Unit ray directions (height, width, 3) in the shelf frame through every pixel centre."""
        u, v = np.meshgrid(np.arange(self.width), np.arange(self.height))
        d_C = np.stack([(u - self.cx) / self.fx, (v - self.cy) / self.fy, np.ones_like(u, dtype=float)], axis=-1)
        d_C /= np.linalg.norm(d_C, axis=-1, keepdims=True)
        return d_C @ self.X_SC[:3, :3].T

    def to_dict(self) -> dict:
        return {
            "X_SC": self.X_SC.tolist(),
            "width": self.width,
            "height": self.height,
            "fx": self.fx,
            "fy": self.fy,
            "cx": self.cx,
            "cy": self.cy,
            "near": self.near,
            "far": self.far,
        }


def camera_pose(position, pitch_deg: float) -> np.ndarray:
    """X_SC for a camera at ``position`` (shelf frame) looking along +y_S, pitched down by ``pitch_deg``."""
    pitch = math.radians(pitch_deg)
    c, s = math.cos(pitch), math.sin(pitch)
    # Columns are x_C (image right), y_C (image down) and z_C (optical axis) expressed in S.
    # At zero pitch: x_C = x_S, y_C = -z_S, z_C = y_S; pitching down tilts z_C toward -z_S.
    R_SC = np.array([[1.0, 0.0, 0.0], [0.0, -s, c], [0.0, -c, -s]])
    X = np.eye(4)
    X[:3, :3] = R_SC
    X[:3, 3] = np.asarray(position, dtype=float)
    return X
