"""The live protocol: JSON text messages over one WebSocket per client.

Client -> server:

* ``{"type": "hello", "role": "driver" | "viewer", "convention": "openxr", "rig": "quest2"}``:
  optional, first; without it a client is a viewer in the ``retarget`` convention. One client
  drives at a time; a second ``driver`` is told so and watches. ``rig`` (a packaged rig's name
  or a rig as JSON) names the cameras of the images a driver sends to an image student.
* ``{"type": "devices", "t": 12.30, "hmd": [x, y, z, qw, qx, qy, qz], "left": [...] | null,
  "right": [...] | null}``: one device sample, exactly a line of a ``.jsonl`` recording
  (:mod:`retarget.motion.device_recording`), in the hello's convention; ``t`` on the client's
  clock, increasing. ``null`` = not tracked (the last pose is held). For an image student it
  may carry ``"images": {"shape": [C, H, W], "data": BASE64}``: the cameras' grayscale frames
  (uint8, row-major, at the student's resolution), the latest of which each step reads.

Server -> client:

* ``{"type": "welcome", "role": ..., "convention": ..., "control_hz": 36.0, "character":
  "human", "bodies": [names]}`` once;
* ``{"type": "pose", "step": k, "t": device time used or null, "latency_ms": ms from that
  sample's arrival to this message, "root": [x, y, z, qw, qx, qy, qz], "body_pos": [[x, y,
  z], ...], "body_quat": [[w, x, y, z], ...]}`` every control step, in the client's convention
  and room (the calibration applied on the way in is undone on the way out);
* ``{"type": "error", "message": ...}`` for a message that was skipped (counted, never fatal).
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from retarget.errors import MotionError
from retarget.motion.device_recording import TO_RETARGET, parse_sample

MAX_MESSAGE_BYTES = 64 * 1024
"""Largest message read; a device sample is a few hundred bytes."""
ROLES = ("driver", "viewer")


class BadMessage(ValueError):
    """A message the server skips (and counts)."""


MAX_IMAGE_BYTES = 8 * 640 * 480


@dataclass
class Hello:
    role: str
    convention: str
    rig: str | None = None  # CameraRig JSON


@dataclass
class Sample:
    t: float
    poses: np.ndarray  # (3, 7) in the client's convention
    tracked: np.ndarray  # (3,)
    images: np.ndarray | None = None  # (C, H, W) uint8


def _images(value: object) -> np.ndarray:
    import base64
    import binascii

    if not isinstance(value, dict) or not isinstance(value.get("data"), str):
        raise BadMessage("'images' must be {\"shape\": [C, H, W], \"data\": base64}")
    shape = value.get("shape")
    if (not isinstance(shape, list) or len(shape) != 3
            or not all(isinstance(v, int) and 0 < v <= 640 for v in shape)):  # fmt: skip
        raise BadMessage("'images.shape' must be three sizes [C, H, W] of 1-640")
    size = shape[0] * shape[1] * shape[2]
    if size > MAX_IMAGE_BYTES or len(value["data"]) > 2 * MAX_IMAGE_BYTES:
        raise BadMessage(f"images of {size} bytes (at most {MAX_IMAGE_BYTES})")
    try:
        raw = base64.b64decode(value["data"], validate=True)
    except (binascii.Error, ValueError):
        raise BadMessage("'images.data' is not base64") from None
    if len(raw) != size:
        raise BadMessage(f"'images.data' holds {len(raw)} bytes, the shape says {size}")
    return np.frombuffer(raw, dtype=np.uint8).reshape(shape)


def _rig(value: object) -> str | None:
    if value is None:
        return None
    from pydantic import ValidationError

    from retarget.motion.camera_rigs import RIGS, CameraRig

    if isinstance(value, str) and value in RIGS:
        return RIGS[value].model_dump_json()
    try:
        return CameraRig.model_validate(value).model_dump_json()
    except ValidationError as exc:
        raise BadMessage(f"'rig' is not a camera rig ({', '.join(RIGS)} or cameras): "
                         f"{exc.errors()[0]['msg']}") from None  # fmt: skip


def parse(text: str | bytes) -> Hello | Sample:
    """A client message; :class:`BadMessage` says what is wrong with one that is not."""
    if isinstance(text, bytes):
        raise BadMessage("messages are JSON text, not binary")
    if len(text) > MAX_MESSAGE_BYTES:
        raise BadMessage(f"message of {len(text)} bytes (at most {MAX_MESSAGE_BYTES})")
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as exc:
        raise BadMessage(f"not JSON: {exc.msg}") from None
    if not isinstance(obj, dict):
        raise BadMessage("a message is a JSON object")
    kind = obj.get("type")
    if kind == "hello":
        role = obj.get("role", "viewer")
        convention = obj.get("convention", "retarget")
        if role not in ROLES:
            raise BadMessage(f"role must be one of {', '.join(ROLES)}")
        if convention not in TO_RETARGET:
            raise BadMessage(f"convention must be one of {', '.join(TO_RETARGET)}")
        return Hello(role, convention, _rig(obj.get("rig")))
    if kind == "devices":
        try:
            t, poses, tracked = parse_sample(obj)
        except MotionError as exc:
            raise BadMessage(exc.message) from None
        images = _images(obj["images"]) if obj.get("images") is not None else None
        return Sample(t, poses, tracked, images)
    raise BadMessage(f"unknown message type {kind!r} (hello, devices)")


def pose_message(step: int, t: float | None, latency_ms: float | None, root: np.ndarray,
                 body_pos: np.ndarray, body_quat: np.ndarray) -> str:  # fmt: skip
    return json.dumps({
        "type": "pose", "step": step, "t": t,
        "latency_ms": None if latency_ms is None else round(latency_ms, 3),
        "root": np.round(root, 5).tolist(), "body_pos": np.round(body_pos, 5).tolist(),
        "body_quat": np.round(body_quat, 5).tolist(),
    })  # fmt: skip
