"""The project's own default motion set, generated on the canonical skeleton.

Used when a recipe names no motion data, so that training, tests and demos work out of the box
without any downloaded dataset. Feet are planted exactly: the generator first lays footprints
along the root path, then solves each leg by analytic two-bone IK (knee towards the heading),
lowering the pelvis where a leg would otherwise over-stretch. Toe-off lifts the heel about the
ball of the foot, so the stance leg is not forced to stay flat-footed.

Clips: ``idle`` (weight shift, breathing, looking around), ``walk`` (straight, 1.1 m/s),
``turn_left``/``turn_right`` (walking on a 2.5 m radius), ``sit_stand`` (sit down on a 0.45 m
seat behind the subject and stand up again).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip, local_from_global
from retarget.motion.contacts import label_contacts
from retarget.motion.floor import align_floor, foot_points

GEN_FPS = 60.0
_J = sk.joint_index


def _rz(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(a), np.ones_like(a)
    return np.stack(
        [np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2
    )


def _ry(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(a), np.ones_like(a)
    return np.stack(
        [np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2
    )


def _rx(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(a), np.ones_like(a)
    return np.stack(
        [np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], -2
    )


def _aim(tdir: np.ndarray, d: np.ndarray, heading: np.ndarray) -> np.ndarray:
    """Rotations ``(T, 3, 3)`` taking ``tdir`` onto ``d`` with the twist of ``heading``."""
    s = rot.to_matrix(rot.between(np.einsum("tij,j->ti", heading, tdir), d))
    return s @ heading


def _smooth(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


class _Body:
    """Builds a clip from root path, heading, trunk lean and ankle targets."""

    def __init__(self, height: float) -> None:
        self.height = height
        self.s = height / sk.REFERENCE_HEIGHT
        self.off = sk.rest_offsets(height)
        self.thigh = float(np.linalg.norm(self.off[_J("left_knee")]))
        self.shin = float(np.linalg.norm(self.off[_J("left_ankle")]))
        self.ankle_h = sk.ANKLE_HEIGHT_175 * self.s
        self.stand_z = sk.standing_pelvis_height(self.off)

    def foot_rotation(self, yaw: np.ndarray, pitch: np.ndarray) -> np.ndarray:
        return _rz(yaw) @ _ry(pitch)

    def ankle_from_toe(self, toe: np.ndarray, yaw: np.ndarray, pitch: np.ndarray) -> np.ndarray:
        r = self.foot_rotation(yaw, pitch)
        return toe - np.einsum("tij,j->ti", r, self.off[_J("left_toe")])

    def build(
        self,
        name: str,
        fps: float,
        root_xy: np.ndarray,
        yaw: np.ndarray,
        ankles: dict[str, np.ndarray],
        foot_pitch: dict[str, np.ndarray],
        *,
        pelvis_drop: np.ndarray | float = 0.0,
        lean: np.ndarray | float = 0.0,
        arm_swing: dict[str, np.ndarray] | None = None,
        head_yaw: np.ndarray | float = 0.0,
        pelvis_z: np.ndarray | None = None,
        foot_yaw: dict[str, np.ndarray] | None = None,
        toe_pitch: dict[str, np.ndarray] | None = None,
    ) -> MotionClip:
        t = yaw.shape[0]
        lean = np.broadcast_to(np.asarray(lean, dtype=np.float64), (t,))
        heading = _rz(yaw)
        g = np.tile(np.eye(3), (t, sk.NUM_JOINTS, 1, 1))
        pelvis_rot = heading @ _ry(0.4 * lean)
        g[:, _J("pelvis")] = pelvis_rot
        # pelvis height: nominal, lowered where a leg could not reach its ankle target
        z = (self.stand_z - pelvis_drop) * np.ones(t) if pelvis_z is None else pelvis_z.copy()
        reach = 0.995 * (self.thigh + self.shin)
        for side in ("left", "right"):
            hip_local = self.off[_J(f"{side}_hip")]
            hip_xy = root_xy + np.einsum("tij,j->ti", pelvis_rot, hip_local)[:, :2]
            horiz = np.linalg.norm(ankles[side][:, :2] - hip_xy, axis=-1)
            dz = np.sqrt(np.maximum(reach**2 - horiz**2, 0.0))
            hip_drop = np.einsum("tij,j->ti", pelvis_rot, hip_local)[:, 2]
            z = np.minimum(z, ankles[side][:, 2] + dz - hip_drop)
        root = np.concatenate([root_xy, z[:, None]], axis=-1)
        for k, name_j in enumerate(("spine", "spine1", "spine2")):
            g[:, _J(name_j)] = heading @ _ry(lean * (0.6 + 0.2 * k))
        breathe = g[:, _J("spine2")]
        g[:, _J("neck")] = heading @ _ry(0.3 * lean)
        g[:, _J("head")] = _rz(yaw + head_yaw)
        for side, sign in (("left", 1.0), ("right", -1.0)):
            g[:, _J(f"{side}_collar")] = breathe
            swing = np.zeros(t) if arm_swing is None else arm_swing[side]
            upper = heading @ _ry(swing) @ _rx(-sign * np.deg2rad(78.0))
            g[:, _J(f"{side}_shoulder")] = upper
            fore = upper @ _rz(-sign * (np.deg2rad(15.0) + 0.5 * np.maximum(-swing, 0)))
            g[:, _J(f"{side}_elbow")] = fore
            g[:, _J(f"{side}_wrist")] = fore
            # legs: analytic two-bone IK, knee towards the heading
            hip = root + np.einsum("tij,j->ti", pelvis_rot, self.off[_J(f"{side}_hip")])
            target = ankles[side]
            d = target - hip
            dist = np.clip(np.linalg.norm(d, axis=-1), abs(self.thigh - self.shin) + 1e-6, reach)
            u = d / np.linalg.norm(d, axis=-1, keepdims=True)
            fwd = heading[:, :, 0]
            n = fwd - np.sum(fwd * u, -1, keepdims=True) * u
            n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-9)
            cos_a = (self.thigh**2 + dist**2 - self.shin**2) / (2 * self.thigh * dist)
            a = np.arccos(np.clip(cos_a, -1.0, 1.0))[:, None]
            knee = hip + self.thigh * (np.cos(a) * u + np.sin(a) * n)
            down = np.array([0.0, 0.0, -1.0])
            g[:, _J(f"{side}_hip")] = _aim(down, knee - hip, heading)
            g[:, _J(f"{side}_knee")] = _aim(down, hip + u * dist[:, None] - knee, heading)
            fy = yaw if foot_yaw is None else foot_yaw[side]
            foot = self.foot_rotation(fy, foot_pitch[side])
            g[:, _J(f"{side}_ankle")] = foot
            tp = foot_pitch[side] if toe_pitch is None else toe_pitch[side]
            g[:, _J(f"{side}_toe")] = self.foot_rotation(fy, tp)
        local = local_from_global(rot.from_matrix(g))
        clip = MotionClip(
            fps, root, local, self.off, name=name, skeleton="canonical", meta={"generated": True}
        )
        clip = align_floor(clip)
        contacts = label_contacts(foot_points(clip), clip.meta["foot_clearance"], fps)  # type: ignore[arg-type]
        return clip.with_(contacts=contacts)


def _walk(
    body: _Body, name: str, seconds: float, fps: float, speed: float, yaw_rate: float
) -> MotionClip:
    period = 1.05  # one stride (two steps), seconds
    stance = 0.62
    t = np.arange(int(seconds * fps)) / fps
    # path and footprints are laid on a finer, longer time grid so stance feet never move
    tt = np.arange(-2 * period, seconds + 2 * period, 1.0 / 240.0)
    ramp_f = _smooth(tt / 1.0)  # start from standing
    yaw_f = yaw_rate * np.cumsum(ramp_f * np.diff(tt, prepend=tt[0]))
    vel = np.stack([np.cos(yaw_f), np.sin(yaw_f)], -1) * (speed * ramp_f)[:, None]
    xy_f = np.cumsum(vel * np.diff(tt, prepend=tt[0])[:, None], axis=0)

    def at(x: np.ndarray, when: np.ndarray) -> np.ndarray:
        return np.stack([np.interp(when, tt, x[:, k]) for k in range(x.shape[1])], -1)

    root_xy = at(xy_f, t)
    yaw = np.interp(t, tt, yaw_f)
    ramp = np.interp(t, tt, ramp_f)
    toe_local = body.off[_J("left_ankle") + 1]  # ankle -> toe in the foot frame
    ankles, pitches, swing_arm, foot_yaw, toe_pitch = {}, {}, {}, {}, {}
    max_pitch = np.deg2rad(28.0)
    for k, (side, sign) in enumerate((("left", 1.0), ("right", -1.0))):
        lateral = np.array([0.0, sign * 0.1 * body.s])
        phase = t / period - 0.5 * k
        n = np.floor(phase)
        phi = phase - n

        def footprint(
            cycle: np.ndarray, lateral: np.ndarray = lateral, k: int = k
        ) -> tuple[np.ndarray, np.ndarray]:
            when = (cycle + 0.5 * k + stance * 0.5) * period
            c = at(xy_f, when)
            y = np.interp(when, tt, yaw_f)
            lat = np.stack(
                [
                    np.cos(y) * lateral[0] - np.sin(y) * lateral[1],
                    np.sin(y) * lateral[0] + np.cos(y) * lateral[1],
                ],
                -1,
            )
            return c + lat, y

        here, yaw_here = footprint(n)
        there, yaw_there = footprint(n + 1)
        # stance: flat, then heel lift about the ball of the foot during toe-off
        lift = max_pitch * _smooth((phi - 0.38) / (stance - 0.38))
        flat_ankle = np.concatenate([here, np.full((t.size, 1), body.ankle_h)], -1)
        flat_toe = flat_ankle + np.einsum(
            "tij,j->ti", body.foot_rotation(yaw_here, np.zeros_like(phi)), toe_local
        )
        stance_ankle = body.ankle_from_toe(flat_toe, yaw_here, lift)
        # swing: from the toe-off pose to the next flat footprint, foot clear of the ground
        s = np.clip((phi - stance) / (1 - stance), 0.0, 1.0)
        end_ankle = np.concatenate([there, np.full((t.size, 1), body.ankle_h)], -1)
        off_ankle = body.ankle_from_toe(flat_toe, yaw_here, np.full_like(phi, max_pitch))
        e = _smooth(s)[:, None]
        swing_ankle = off_ankle * (1 - e) + end_ankle * e
        swing_ankle[:, 2] += 0.07 * body.s * np.sin(np.pi * s) * (speed > 0)
        in_swing = (phi >= stance)[:, None]
        ankles[side] = np.where(in_swing, swing_ankle, stance_ankle)
        pitches[side] = np.where(phi >= stance, max_pitch * (1 - _smooth(s / 0.6)), lift)
        # the toes stay flat on the ground while the heel lifts, then follow the foot
        toe_pitch[side] = np.where(phi >= stance, pitches[side] * _smooth(s / 0.15), 0.0)
        foot_yaw[side] = np.where(
            phi >= stance, yaw_here + (yaw_there - yaw_here) * _smooth(s), yaw_here
        )
        swing_arm[side] = -np.deg2rad(18.0) * np.sin(2 * np.pi * phase) * ramp
    bob = 0.015 * body.s * (1 - np.cos(4 * np.pi * t / period)) * ramp
    return body.build(
        name,
        fps,
        root_xy,
        yaw,
        ankles,
        pitches,
        pelvis_drop=0.03 * body.s + bob,
        lean=np.deg2rad(4.0) * ramp,
        arm_swing=swing_arm,
        foot_yaw=foot_yaw,
        toe_pitch=toe_pitch,
    )


def _idle(body: _Body, fps: float, seconds: float = 6.0) -> MotionClip:
    t = np.arange(int(seconds * fps)) / fps
    yaw = np.zeros_like(t)
    sway = 0.025 * body.s * np.sin(2 * np.pi * t / 4.0)
    root_xy = np.stack([np.zeros_like(t), sway], -1)
    ankles, pitches = {}, {}
    for side, sign in (("left", 1.0), ("right", -1.0)):
        a = np.array([0.0, sign * 0.11 * body.s, body.ankle_h])
        ankles[side] = np.tile(a, (t.size, 1))
        pitches[side] = np.zeros_like(t)
    breathe = np.deg2rad(1.5) * np.sin(2 * np.pi * t / 3.5)
    swing = {
        "left": np.deg2rad(4.0) * np.sin(2 * np.pi * t / 3.5),
        "right": np.deg2rad(4.0) * np.sin(2 * np.pi * t / 3.5 + 1.0),
    }
    look = np.deg2rad(25.0) * np.sin(2 * np.pi * t / 6.0)
    return body.build(
        "idle",
        fps,
        root_xy,
        yaw,
        ankles,
        pitches,
        pelvis_drop=0.01 * body.s,
        lean=breathe,
        arm_swing=swing,
        head_yaw=look,
    )


def _sit_stand(body: _Body, fps: float) -> MotionClip:
    seconds = 7.0
    t = np.arange(int(seconds * fps)) / fps
    down = _smooth((t - 1.0) / 1.6)
    up = _smooth((t - 4.2) / 1.6)
    seated = down - up  # 0 standing, 1 seated
    moving = np.sin(np.pi * np.clip((t - 1.0) / 1.6, 0, 1)) + np.sin(
        np.pi * np.clip((t - 4.2) / 1.6, 0, 1)
    )
    yaw = np.zeros_like(t)
    root_xy = np.stack([-0.32 * body.s * seated, np.zeros_like(t)], -1)
    seat_pelvis = 0.45 * body.s + 0.09 * body.s
    z = body.stand_z * (1 - seated) + seat_pelvis * seated
    ankles, pitches = {}, {}
    for side, sign in (("left", 1.0), ("right", -1.0)):
        a = np.array([0.06 * body.s, sign * 0.12 * body.s, body.ankle_h])
        ankles[side] = np.tile(a, (t.size, 1))
        pitches[side] = np.zeros_like(t)
    lean = np.deg2rad(38.0) * moving + np.deg2rad(5.0) * seated
    swing = {"left": -np.deg2rad(25.0) * seated, "right": -np.deg2rad(25.0) * seated}
    return body.build(
        "sit_stand", fps, root_xy, yaw, ankles, pitches, lean=lean, arm_swing=swing, pelvis_z=z
    )


GENERATORS: dict[str, Callable[[_Body, float], MotionClip]] = {
    "idle": lambda b, fps: _idle(b, fps),
    "walk": lambda b, fps: _walk(b, "walk", 8.0, fps, 1.1 * b.s, 0.0),
    "turn_left": lambda b, fps: _walk(b, "turn_left", 8.0, fps, 1.0 * b.s, 1.0 / 2.5),
    "turn_right": lambda b, fps: _walk(b, "turn_right", 8.0, fps, 1.0 * b.s, -1.0 / 2.5),
    "sit_stand": lambda b, fps: _sit_stand(b, fps),
}


def idle_clip(
    seconds: float, height: float = sk.REFERENCE_HEIGHT, fps: float = GEN_FPS
) -> MotionClip:
    """A standing idle of ``seconds``: the start pose and placeholder body motion when a
    policy is driven by recorded devices instead of motion capture."""
    return _idle(_Body(height), fps, seconds)


def default_motions(
    height: float = sk.REFERENCE_HEIGHT, fps: float = GEN_FPS, names: tuple[str, ...] | None = None
) -> list[MotionClip]:
    """The generated default set (all clips, or those in ``names``) for a subject's height."""
    body = _Body(height)
    wanted = tuple(GENERATORS) if names is None else names
    unknown = [n for n in wanted if n not in GENERATORS]
    if unknown:
        raise KeyError(f"unknown generated motions {unknown}; known: {', '.join(GENERATORS)}")
    return [GENERATORS[n](body, fps) for n in wanted]
