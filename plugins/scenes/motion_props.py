"""``motion_props``: the props a motion implies, per clip: given, from a sidecar, or fitted.

For every clip of the run, in this order of precedence:

1. ``clips.NAME`` in the scene's config (a recipe field): the clip's props, listed;
2. a sidecar ``CLIP.scene.yaml`` next to the clip's motion file (``walk.bvh`` ->
   ``walk.scene.yaml``) holding ``props: [...]`` in the same form;
3. the scene recorded with the clip: an ``.obj`` (or ``.ply``/``.glb``) in the clip file's own
   folder, each closed piece an upright box (:mod:`retarget.scene.mesh_boxes`; the box-climb
   captures keep ``multi_boxes.obj`` beside each sequence), with ``meshes: true``;
4. with ``auto: true`` (the default), the props fitted to the motion
   (:mod:`retarget.motion.scene_fit`): a seat under a pelvis that is low and still for 0.5 s,
   boxes under feet that rest above the floor.

A prop is ``{kind: seat|box, position: [x, y], yaw, height, size: [x, y]}``: a box standing
on the floor with its top at ``height``. All clips' props go into one world (clips recorded
in one room share its coordinates); props of different clips that overlap are the user's to
sort out through ``clips`` or sidecars, or with ``per_clip: true``: then an episode sees only
its own clip's props (the others are parked far away), and identical props of several clips
(within 2 cm and 0.02 rad) are one prop they share. The props are mocap bodies like every other prop
scene's, randomized per episode (Sec. 3.4), and the reference contact labels are computed
against their un-randomized placement.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Literal

from pydantic import Field, ValidationError

import retarget
from retarget.errors import PluginError
from retarget.kinds import PluginConfig
from retarget.scene.props import Prop, PropScene, PropSetConfig, box

if TYPE_CHECKING:
    from retarget.motion.clip import MotionClip
    from retarget.motion.scene_fit import FittedProp


class PropSpec(PluginConfig):
    """One box on the floor a clip needs (a seat or a step)."""

    kind: Literal["seat", "box"] = "box"
    position: tuple[float, float] = Field(description="world x, y of its centre, metres")
    yaw: float = Field(0.0, description="rotation about +Z, radians")
    height: float = Field(gt=0, description="its top above the floor, metres")
    size: tuple[float, float] = Field((0.45, 0.45), description="x, y extents, metres")


class ClipProps(PluginConfig):
    props: tuple[PropSpec, ...] = ()


class MotionPropsConfig(PropSetConfig):
    clips: dict[str, tuple[PropSpec, ...]] = Field(
        default_factory=dict, description="clip name -> its props (wins over sidecar and auto)"
    )
    sidecar: bool = Field(True, description="read CLIP.scene.yaml next to a clip's motion file")
    meshes: bool = Field(True, description="read the boxes of a mesh beside a clip's file")
    auto: bool = Field(True, description="fit seats and boxes to clips without given props")
    per_clip: bool = Field(
        False, description="an episode sees only its clip's props (others parked far away)"
    )
    snap_tops: float = Field(
        0.05, ge=0, le=0.2,
        description="a mesh box whose top is within this many metres of where the clip's feet "
        "rest on it is moved to meet them (a capture and its scan disagree by centimetres)",
    )  # fmt: skip


def sidecar_path(source: Path) -> Path:
    """``dir/walk.bvh`` -> ``dir/walk.scene.yaml``."""
    return source.with_name(f"{source.stem}.scene.yaml")


def read_sidecar(path: Path) -> tuple[PropSpec, ...]:
    """The props of a sidecar file; errors name the file and the field."""
    import yaml
    try:
        raw = yaml.safe_load(path.read_text()) or {}
        return ClipProps.model_validate(raw).props
    except ValidationError as exc:
        err = exc.errors()[0]
        where = ".".join(str(p) for p in err["loc"])
        raise PluginError(
            f"{err['msg']}", file=path, field=where, plugin="scene motion_props"
        ) from exc
    except yaml.YAMLError as exc:
        raise PluginError(f"not YAML: {exc}", file=path, plugin="scene motion_props") from exc


def _spec(p: FittedProp) -> PropSpec:
    return PropSpec(kind=p.kind, position=p.position, yaw=p.yaw, height=p.height, size=p.size)


PARK = (-50.0, -50.0)
"""Where props of other clips stand during an episode (``per_clip``): far from any motion."""


def mesh_specs(path: Path) -> tuple[PropSpec, ...]:
    from retarget.scene.mesh_boxes import boxes_from_mesh

    return tuple(PropSpec(kind="box", position=b.position, yaw=b.yaw, height=b.height,
                          size=b.size) for b in boxes_from_mesh(path))  # fmt: skip


def scale_of(clip: MotionClip) -> float:
    return float(clip.meta.get("scale", 1.0))  # type: ignore[arg-type]


def _snapped(boxes: tuple[PropSpec, ...], clip: MotionClip, tolerance: float):
    """Mesh boxes (in the clip's own frame) with their tops moved to where the clip's feet
    rest on them, when that is within ``tolerance``."""
    if tolerance <= 0:
        return boxes
    import math

    from retarget.motion.scene_fit import fit_boxes

    k = scale_of(clip)
    rests = [r for r in fit_boxes(clip)]  # the clip is at the character's scale: divide by k
    out = []
    for b in boxes:
        c, s_ = math.cos(b.yaw), math.sin(b.yaw)
        tops = []
        for r in rests:
            dx, dy = r.position[0] / k - b.position[0], r.position[1] / k - b.position[1]
            u, v = c * dx + s_ * dy, -s_ * dx + c * dy
            if abs(u) <= b.size[0] / 2 and abs(v) <= b.size[1] / 2:
                tops.append(r.height / k)
        near = [t for t in tops if abs(t - b.height) <= tolerance]
        if near:
            b = b.model_copy(update={"height": float(sorted(near)[len(near) // 2])})
        out.append(b)
    return tuple(out)


def _scaled(p: PropSpec, k: float) -> PropSpec:
    """A prop given in the clip's frame moved to the character's scale (see
    ``scaled_clip``): positions, extents and height times ``k``."""
    return p.model_copy(update={"position": (p.position[0] * k, p.position[1] * k),
                                "size": (p.size[0] * k, p.size[1] * k), "height": p.height * k})


def _same(a: PropSpec, b: PropSpec) -> bool:
    return (a.kind == b.kind and abs(a.height - b.height) < 0.02 and abs(a.yaw - b.yaw) < 0.02
            and max(abs(x - y) for x, y in zip(a.position + a.size, b.position + b.size,
                                               strict=True)) < 0.02)  # fmt: skip


class MotionProps(PropScene[MotionPropsConfig]):
    """Seats and boxes where the motions need them: listed, from sidecars, or fitted."""

    name = "motion_props"

    def __init__(self, config: PluginConfig | None = None) -> None:
        import torch

        self._specs: list[tuple[str, PropSpec]] = []
        self._owners = torch.zeros(0, 0, dtype=torch.bool)  # (clips, props): who sees what
        self._episode_clip = torch.zeros(0, dtype=torch.long)
        super().__init__(config)

    def fit_motion(self, clips: Sequence[MotionClip]) -> None:
        from retarget.motion.scene_fit import fit_props
        cfg: MotionPropsConfig = self.config  # type: ignore[assignment]
        import torch

        specs: list[tuple[str, PropSpec]] = []
        owners: list[set[int]] = []
        for c, clip in enumerate(clips):
            mesh = None
            if cfg.meshes and clip.source is not None and clip.source.parent.is_dir():
                from retarget.scene.mesh_boxes import mesh_beside

                mesh = mesh_beside(clip.source)
            fitted = False
            if clip.name in cfg.clips:
                found = cfg.clips[clip.name]
            elif cfg.sidecar and clip.source is not None and sidecar_path(clip.source).exists():
                found = read_sidecar(sidecar_path(clip.source))
            elif mesh is not None:
                found = _snapped(mesh_specs(mesh), clip, cfg.snap_tops / scale_of(clip))
            elif cfg.auto:
                found, fitted = tuple(_spec(p) for p in fit_props(clip)), True
            else:
                found = ()
            scale = scale_of(clip)
            if scale != 1.0 and not fitted:  # given in the clip's frame: to the character's
                found = tuple(_scaled(s, scale) for s in found)
            for spec in found:
                same = next((i for i, (_, s) in enumerate(specs) if _same(s, spec)), None)
                if cfg.per_clip and same is not None:
                    owners[same].add(c)
                    continue
                specs.append((clip.name, spec))
                owners.append({c})
        self._specs = specs
        self._owners = torch.zeros(len(clips), len(specs), dtype=torch.bool)
        for p, who in enumerate(owners):
            self._owners[list(who), p] = True
        self._props = self.placed_props()
        self._tables = self._flatten()
        if self._allocated:  # placements of the old props mean nothing for the new ones
            self.allocate(self._offsets.shape[0])

    def allocate(self, num_envs: int) -> None:
        import torch

        super().allocate(num_envs)
        self._episode_clip = torch.full((num_envs,), -1, dtype=torch.long)

    def start_episodes(self, env_ids, clip, seconds) -> None:
        if not self._allocated:
            self.allocate(int(env_ids.max()) + 1)
        self._episode_clip[env_ids] = clip.long()

    def randomize(self, env_ids, generator) -> None:
        """The configured noise, then (``per_clip``) other clips' props parked."""
        import torch

        super().randomize(env_ids, generator)
        cfg: MotionPropsConfig = self.config  # type: ignore[assignment]
        if not cfg.per_clip or not self._specs or env_ids.numel() == 0:
            return
        clip = self._episode_clip[env_ids]
        seen = torch.where(clip[:, None] >= 0, self._owners[clip.clamp(min=0)], True)
        base = self._tables.base[:, :2]  # (P, 2)
        park = torch.tensor(PARK, dtype=base.dtype) - base
        offsets = self._offsets[env_ids]
        offsets[..., :2] = torch.where(seen[..., None], offsets[..., :2], park)
        self._offsets[env_ids] = offsets

    def reference_placement(self, clip: int):
        """With ``per_clip``: the clip's own props where they stand, the others parked."""
        import torch

        from retarget.geometry.heading import yaw_quat

        cfg: MotionPropsConfig = self.config  # type: ignore[assignment]
        if not cfg.per_clip or not self._specs or clip >= self._owners.shape[0]:
            return None
        base = self._tables.base  # (P, 3): x, y, yaw
        pos = torch.cat([base[:, :2], torch.zeros_like(base[:, :1])], dim=-1)
        seen = self._owners[clip]
        pos[~seen, :2] = torch.tensor(PARK, dtype=pos.dtype)
        return pos, yaw_quat(base[:, 2])

    def props(self) -> list[Prop]:
        out = []
        for i, (clip, s) in enumerate(self._specs):
            part = box((s.size[0], s.size[1], s.height), (0.0, 0.0, s.height / 2))
            out.append(Prop(f"{clip}_{s.kind}{i}", (part,), xy=s.position, yaw=s.yaw))
        return out

    def placed_props(self) -> list[Prop]:
        return self.props()  # positions are world positions already

    @property
    def fitted(self) -> list[PropSpec]:
        """The props in the world, in order."""
        return [s for _, s in self._specs]


@retarget.hookimpl
def register_scenes(register) -> None:
    register(MotionProps)
