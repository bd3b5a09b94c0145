"""What ``slax-drake plan-step`` carries from one call to the next so that a real robot's search keeps the memory a
simulated trial keeps.

A policy remembers its own trial: the arrangements it observed, the actions that failed when executed, the last
move of each object (the corrections of :mod:`slax_drake.policies.policies`), and slax-belief its worlds and plan.
Each plan-step call is a new process, so that memory would start empty at every step and a real robot could repeat
a push that moved nothing or move an object back and forth. The step file therefore records, for every step that
planned a motion, the frame it was planned on and what was decided there; the next call replays those steps through
the same perception and policy (each rejected candidate excluded again, in order) before it decides on its own
frame. Policies are deterministic, so the replay rebuilds their memory exactly, and it is checked: each replayed
step must choose the action that step chose, or the step file is refused (another policy, code version or frame).

One step's record (JSON): ``depth`` and ``mask``, the frame at the policies' working resolution (float32 metres and
one bit per pixel, zlib-compressed, base64), ``shape`` ``[rows, columns]``, ``joint_state`` (the nine planned
joints), ``rejected`` (the candidates the planner or the checker refused, in order: ``candidate``, the action as
the step file's ``action`` describes one, with ``reason`` and ``whole_group``) and ``action`` (the one planned).
About 70 kB per step.
"""

from __future__ import annotations

import base64
import binascii
import zlib

import numpy as np

from slax_drake.errors import PlanStepError


def _pack(data: bytes) -> str:
    return base64.b64encode(zlib.compress(data, 6)).decode("ascii")


def _unpack(text, what: str, step: int) -> bytes:
    try:
        return zlib.decompress(base64.b64decode(str(text), validate=True))
    except (binascii.Error, zlib.error, ValueError) as e:
        raise PlanStepError(f"history step {step}: its {what} is corrupt ({e})") from None


def encode_frame(depth: np.ndarray, mask: np.ndarray, joint_state) -> dict:
    """The record of a working-resolution frame (``depth`` m, ``mask`` the target's pixels) and the joint state."""
    depth = np.ascontiguousarray(depth, dtype="<f4")
    mask = np.asarray(mask, dtype=bool)
    return {"shape": [int(depth.shape[0]), int(depth.shape[1])], "depth": _pack(depth.tobytes()),
            "mask": _pack(np.packbits(mask.ravel()).tobytes()),
            "joint_state": None if joint_state is None else [float(v) for v in joint_state]}


def decode_frame(record, step: int) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(depth float32 m, mask bool, joint state or None) of a step record; PlanStepError when it is malformed."""
    if not isinstance(record, dict) or not all(k in record for k in ("shape", "depth", "mask")):
        raise PlanStepError(f"history step {step}: expected a frame record with shape, depth and mask")
    try:
        rows, cols = (int(v) for v in record["shape"])
    except (TypeError, ValueError):
        raise PlanStepError(f"history step {step}: shape must be [rows, columns]") from None
    if rows <= 0 or cols <= 0:
        raise PlanStepError(f"history step {step}: shape must be positive, got {record['shape']}")
    depth = np.frombuffer(_unpack(record["depth"], "depth", step), dtype="<f4")
    bits = np.frombuffer(_unpack(record["mask"], "mask", step), dtype=np.uint8)
    if depth.size != rows * cols or bits.size != (rows * cols + 7) // 8:
        raise PlanStepError(f"history step {step}: depth or mask does not hold {rows}x{cols} pixels")
    mask = np.unpackbits(bits)[: rows * cols].astype(bool).reshape(rows, cols)
    q = record.get("joint_state")
    try:
        q = None if q is None else np.asarray(q, dtype=float)
    except (TypeError, ValueError):
        raise PlanStepError(f"history step {step}: joint_state must be numbers") from None
    return depth.reshape(rows, cols).astype(np.float32), mask, q
