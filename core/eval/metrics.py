"""Per-step tracking metrics, vectorised over environments.

Device errors compare the simulated character's mounts (head, hands) with the kinematic
reference's mounts, which for the human character are the user's devices themselves. The
QuestEnvSim failure rule (mean headset/controller error above 0.8 m) stops counting errors and
jerk for that run; the SimXR rule (head farther than 0.5 m from the headset at any frame) is
tracked separately. Joint errors (MPJPE family) use the character's ``common_joints`` body
group when it has one (the 11 joints SimXR reports).

Scene interaction: ``scene_contact_agree`` is the fraction of QuestEnvSim's contact links
(feet, hands, pelvis, spine: those body groups the character has) whose simulated contact
state (upward contact force above 50 N, the ``contact`` reward's rule) equals the reference's
scene label; ``penetration_max``/``penetration_mean`` are the deepest and mean overlap of the
character's geoms into scene geoms (floor included) among MuJoCo's contacts (``dist < 0``),
given by the runner from :meth:`BatchedSim.penetration`. Feet hitting props (box tops and
sides, the boxes-on-a-path check) come from MuJoCo's contact list too, in
:mod:`retarget.eval.prop_hits`, counted by the runner.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from retarget.geometry.heading import quat_apply, rotation_distance
from retarget.kinds.state import Layout, StepContext
from retarget.scene.contacts import CONTACT_LINKS
from retarget.scene.contacts import CONTACT_NEWTONS as LINK_NEWTONS

CONTACT_NEWTONS = 1.0


def procrustes_error(pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Mean joint error after the best similarity transform, per env: (N, J, 3) -> (N,)."""
    mu_p, mu_t = pred.mean(1, keepdim=True), target.mean(1, keepdim=True)
    p, t = pred - mu_p, target - mu_t
    cov = p.transpose(1, 2) @ t
    u, s, vh = torch.linalg.svd(cov)
    d = torch.sign(torch.linalg.det(u @ vh))
    flip = torch.ones_like(s)
    flip[:, -1] = d
    rot = u @ torch.diag_embed(flip) @ vh
    scale = (s * flip).sum(-1) / p.square().sum((1, 2)).clamp_min(1e-12)
    aligned = scale[:, None, None] * p @ rot + mu_t
    return (aligned - target).norm(dim=-1).mean(-1)


def head_to_headset(
    ctx: StepContext, head: int, mount: torch.Tensor | None = None
) -> torch.Tensor:
    """Distance from each environment's simulated headset mount to the headset it was given
    at this frame, metres ``(N,)`` (SimXR's failure rule reads it against 0.5 m).

    ``mount`` is where the headset sits in the ``head`` site's frame
    (:attr:`RetargetEnv.headset_mount`, ``(3,)``); None: at the head site itself."""
    headset = ctx.ref.devices[:, ctx.ref.window_offsets.index(0), 0, :3]
    worn = ctx.sim.site_pos[:, head]
    if mount is not None:
        worn = worn + quat_apply(ctx.sim.site_quat[:, head], mount.to(worn.dtype).expand_as(worn))
    return (worn - headset).norm(dim=-1)


def hands_to_controllers(ctx: StepContext, hands: list[int]) -> torch.Tensor:
    """Mean distance from each environment's simulated hand sites (where a controller is
    held) to the two controllers it was given at this frame, metres ``(N,)``.

    Beside ``controller_cm`` (hands against the reference *character's* hands) this is what a
    VR user sees: the controllers come from the person, whose arms need not have the
    character's proportions, so a character can match its reference and still hold its hands
    away from the person's."""
    controllers = ctx.ref.devices[:, ctx.ref.window_offsets.index(0), 1:3, :3]
    return (ctx.sim.site_pos[:, hands] - controllers).norm(dim=-1).mean(-1)


@dataclass
class StepMetrics:
    """Metrics of one step for every environment, all (N,) float tensors (metres, radians)."""

    hmd_pos: torch.Tensor
    hmd_rot: torch.Tensor
    controller_pos: torch.Tensor  # the hands (where controllers are held), metres
    device_mean: torch.Tensor
    head_to_headset: torch.Tensor
    contact_agree: torch.Tensor
    skate: torch.Tensor  # horizontal foot displacement this step while in contact, metres
    g_mpjpe: torch.Tensor | None = None
    mpjpe: torch.Tensor | None = None
    pa_mpjpe: torch.Tensor | None = None
    mpjre: torch.Tensor | None = None
    mpjve: torch.Tensor | None = None
    scene_contact_agree: torch.Tensor | None = None
    penetration_max: torch.Tensor | None = None  # metres, deepest overlap this step
    penetration_mean: torch.Tensor | None = None  # metres, mean over overlapping contacts
    feet_pos: torch.Tensor | None = None  # metres, mean position error of the feet bodies
    hand_gap: torch.Tensor | None = None  # metres, hands to the given controllers


class MetricProbe:
    """Resolves indices once, then computes :class:`StepMetrics` from step contexts."""

    def __init__(self, layout: Layout, headset_mount: torch.Tensor | None = None) -> None:
        """``headset_mount``: where the headset sits on the head (:func:`head_to_headset`)."""
        self.head = layout.site("head")
        self.headset_mount = headset_mount
        self.hands = [layout.site("left_hand"), layout.site("right_hand")]
        groups = layout.body_groups
        sides = ("left_foot", "right_foot")
        self.sides = (
            [torch.tensor(groups[s]) for s in sides] if all(s in groups for s in sides) else None
        )
        self.feet = torch.tensor(groups["feet"])
        joints = groups.get("common_joints")
        self.joints = torch.tensor(joints) if joints else None
        links = [g for g in CONTACT_LINKS if g in groups]
        names = list(groups)
        self.link_columns = torch.tensor([names.index(g) for g in links], dtype=torch.long)
        bodies = sorted({i for g in links for i in groups[g]})
        member = torch.zeros(len(bodies), len(links))
        for j, g in enumerate(links):
            for i in groups[g]:
                member[bodies.index(i), j] = 1.0
        self.link_bodies, self.link_member = torch.tensor(bodies, dtype=torch.long), member

    def __call__(
        self, ctx: StepContext, penetration: tuple[torch.Tensor, torch.Tensor] | None = None
    ) -> StepMetrics:
        s, r = ctx.sim, ctx.ref.pose
        hmd = (s.site_pos[:, self.head] - r.site_pos[:, self.head]).norm(dim=-1)
        hmd_rot = rotation_distance(r.site_quat[:, self.head], s.site_quat[:, self.head])
        ctrl = (s.site_pos[:, self.hands] - r.site_pos[:, self.hands]).norm(dim=-1)
        device_mean = (hmd + ctrl.sum(-1)) / 3.0
        head_gap = head_to_headset(ctx, self.head, self.headset_mount)
        force = s.contact_force
        if self.sides is not None and ctx.ref.contacts.shape[1] == 2:
            sim_contact = torch.stack(
                [(force[:, idx] > CONTACT_NEWTONS).any(-1) for idx in self.sides], dim=1
            )
            agree = (sim_contact == ctx.ref.contacts).float().mean(-1)
        else:
            agree = torch.full_like(hmd, float("nan"))
        feet_down = force[:, self.feet] > CONTACT_NEWTONS
        speed = s.body_linvel[:, self.feet, :2].norm(dim=-1) * ctx.dt
        skate = (speed * feet_down).sum(-1) / feet_down.sum(-1).clamp_min(1)
        out = StepMetrics(hmd, hmd_rot, ctrl.mean(-1), device_mean, head_gap, agree, skate)
        out.feet_pos = (s.body_pos[:, self.feet] - r.body_pos[:, self.feet]).norm(dim=-1).mean(-1)
        if ctx.ref.devices.shape[2] >= 3:
            out.hand_gap = hands_to_controllers(ctx, self.hands)
        labels = ctx.ref.scene_contacts
        if labels is not None and self.link_columns.numel():
            up = s.contact_force_up[:, self.link_bodies] @ self.link_member
            sim_links = up > LINK_NEWTONS
            ref_links = labels[:, self.link_columns]
            out.scene_contact_agree = (sim_links == ref_links).float().mean(-1)
        if penetration is not None:
            out.penetration_max, out.penetration_mean = penetration
        if self.joints is not None:
            sj, rj = s.body_pos[:, self.joints], r.body_pos[:, self.joints]
            out.g_mpjpe = (sj - rj).norm(dim=-1).mean(-1)
            rel_s = sj - s.site_pos[:, None, self.head]
            rel_r = rj - r.site_pos[:, None, self.head]
            out.mpjpe = (rel_s - rel_r).norm(dim=-1).mean(-1)
            out.pa_mpjpe = procrustes_error(sj, rj)
            out.mpjre = rotation_distance(
                r.body_quat[:, self.joints], s.body_quat[:, self.joints]
            ).mean(-1)
            dv = s.body_linvel[:, self.joints] - r.body_linvel[:, self.joints]
            out.mpjve = dv.norm(dim=-1).mean(-1) * ctx.dt
        return out
