"""``motion_props``: the props a motion implies, per clip: given, from a sidecar, or fitted.

For every clip of the run, in this order of precedence:

1. ``clips.NAME`` in the scene's config (a recipe field): the clip's props, listed;
2. a sidecar ``CLIP.scene.yaml`` next to the clip's motion file (``walk.bvh`` ->
   ``walk.scene.yaml``) holding ``props: [...]`` in the same form;
3. with ``auto: true`` (the default), the props fitted to the motion
   (:mod:`retarget.motion.scene_fit`): a seat under a pelvis that is low and still for 0.5 s,
   boxes under feet that rest above the floor.

A prop is ``{kind: seat|box, position: [x, y], yaw, height, size: [x, y]}``: a box standing
on the floor with its top at ``height``. All clips' props go into one world (clips recorded
in one room share its coordinates); props of different clips that overlap are the user's to
sort out through ``clips`` or sidecars. The props are mocap bodies like every other prop
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
from retarget.scene.props import Prop, PropScene, Randomization, box

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


class MotionPropsConfig(PluginConfig):
    clips: dict[str, tuple[PropSpec, ...]] = Field(
        default_factory=dict, description="clip name -> its props (wins over sidecar and auto)"
    )
    sidecar: bool = Field(True, description="read CLIP.scene.yaml next to a clip's motion file")
    auto: bool = Field(True, description="fit seats and boxes to clips without given props")
    density: float = Field(500.0, gt=0, description="kg/m^3 of every part (uniform density)")
    randomize: Randomization = Field(default_factory=Randomization)


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


class MotionProps(PropScene):
    """Seats and boxes where the motions need them: listed, from sidecars, or fitted."""

    name = "motion_props"
    Config = MotionPropsConfig

    def __init__(self, config: PluginConfig | None = None) -> None:
        self._specs: list[tuple[str, PropSpec]] = []
        super().__init__(config)

    def fit_motion(self, clips: Sequence[MotionClip]) -> None:
        from retarget.motion.scene_fit import fit_props
        cfg: MotionPropsConfig = self.config  # type: ignore[assignment]
        specs: list[tuple[str, PropSpec]] = []
        for clip in clips:
            if clip.name in cfg.clips:
                found = cfg.clips[clip.name]
            elif cfg.sidecar and clip.source is not None and sidecar_path(clip.source).exists():
                found = read_sidecar(sidecar_path(clip.source))
            elif cfg.auto:
                found = tuple(_spec(p) for p in fit_props(clip))
            else:
                found = ()
            specs.extend((clip.name, s) for s in found)
        self._specs = specs
        self._props = self.placed_props()
        self._tables = self._flatten()
        if self._allocated:  # placements of the old props mean nothing for the new ones
            self.allocate(self._offsets.shape[0])

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
