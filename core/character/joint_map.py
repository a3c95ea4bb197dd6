"""Which human joints drive which character joints, and how (kinematic retargeting's recipe).

The paper retargets "by matching selected joint angles": conceptually similar joints of the
human and the creature are paired by hand, and everything unpaired (tails, ears) stays at its
default. A :class:`JointMap` is that pairing as data, so a recipe can change it (bend Dino's spine
more, damp Oppy's arm swing) without touching code:

* keys are **character joints** (a hinge group built by :mod:`retarget.character.builder`, e.g.
  ``l_hip`` with hinges ``l_hip_y, l_hip_z, l_hip_x``);
* ``human`` lists one or more canonical joints whose local rotations (relative to the T-pose) are
  composed parent-first, e.g. ``[left_collar, left_shoulder]`` for a character without collars;
* ``axes`` says which human axis feeds each character hinge (``"-y"`` flips it); by default the
  hinge's own axis, which is right whenever the character is built in the canonical frame
  (X forward, Y left, Z up, world-aligned joint frames at the zero pose);
* ``scale`` multiplies every angle (``0.25`` to spread one human joint over four spine joints)
  and ``offset`` (degrees, per hinge) shifts it, e.g. to lean Dino's body forward;
* ``bend`` (the bone axis) drives a hinge by the angle the bone bends, for elbows: sources
  disagree on whether forearm twist sits in the shoulder or the elbow rotation, which moves the
  Euler flexion angle around but not the bend.

The composed human rotation is decomposed into intrinsic Euler angles about the ``axes``
sequence (completed with the missing axes, which are dropped), matching how MuJoCo composes the
hinges of one body.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel, ConfigDict, Field, field_validator

from retarget.errors import RecipeError

if TYPE_CHECKING:
    import numpy as np

_AXIS_INDEX = {"x": 0, "y": 1, "z": 2}


class JointLink(BaseModel):
    """How one character joint is driven by the human."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    human: tuple[str, ...] = Field(
        description="canonical human joint(s); several are composed parent first"
    )
    axes: tuple[str, ...] | None = Field(
        None, description="human axis per character hinge, e.g. ['y', '-z'] (default: same)"
    )
    scale: float = Field(1.0, description="factor applied to every angle")
    offset: tuple[float, ...] | None = Field(
        None, description="degrees added per hinge after scaling (default 0)"
    )
    bend: str | None = Field(
        None,
        description="bone axis (x, y or z) of the human joint: drive the first hinge by "
        "the bend angle between the bone before and after the rotation, "
        "signed by the first of `axes`; other hinges stay at 0",
    )

    @field_validator("bend")
    @classmethod
    def _bend_axis(cls, v: str | None) -> str | None:
        if v is not None and v.lstrip("+-") not in _AXIS_INDEX:
            raise ValueError(f"bend must name the bone axis x, y or z, got {v!r}")
        return v

    @field_validator("human", mode="before")
    @classmethod
    def _one_or_many(cls, v: Any) -> Any:
        return (v,) if isinstance(v, str) else v

    @field_validator("axes", mode="before")
    @classmethod
    def _axes_string(cls, v: Any) -> Any:
        if isinstance(v, str):  # "xy" or "-y" shorthands
            out, sign = [], ""
            for ch in v:
                if ch in "+-":
                    sign = ch if ch == "-" else ""
                    continue
                out.append(sign + ch)
                sign = ""
            return tuple(out)
        return v

    @field_validator("axes")
    @classmethod
    def _valid_axes(cls, v: tuple[str, ...] | None) -> tuple[str, ...] | None:
        if v is None:
            return v
        bare = [a.lstrip("+-") for a in v]
        bad = [a for a in bare if a not in _AXIS_INDEX]
        if bad:
            raise ValueError(f"axes must be x, y or z with an optional '-', got {list(v)}")
        if len(set(bare)) != len(bare):
            raise ValueError(f"axes must be distinct, got {list(v)}")
        return v


class JointMap(BaseModel):
    """Character joint -> :class:`JointLink`; unlisted character joints stay at their default."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    links: dict[str, JointLink] = Field(default_factory=dict)

    def with_overrides(
        self, overrides: Mapping[str, JointLink | Mapping[str, Any] | None]
    ) -> JointMap:
        """A copy with some links replaced (a mapping) or removed (``None``).

        A mapping override is merged into the existing link, so a recipe can change only
        ``scale`` of ``spine0`` without restating which human joint drives it.
        """
        links = dict(self.links)
        for name, value in overrides.items():
            if value is None:
                links.pop(name, None)
            elif isinstance(value, JointLink):
                links[name] = value
            else:
                base = links[name].model_dump(exclude_unset=True) if name in links else {}
                try:
                    links[name] = JointLink.model_validate({**base, **dict(value)})
                except ValueError as exc:
                    raise RecipeError(
                        f"joint_map override for character joint '{name}': {exc}",
                        field=f"joint_map.{name}",
                    ) from None
        return JointMap(links=links)

    def validate_against(
        self,
        human_joints: Sequence[str],
        character_joints: Mapping[str, Sequence[str]],
        *,
        passive: Iterable[str] = (),
        plugin: str | None = None,
    ) -> None:
        """Check every name and arity; the error names the offending joint and the choices.

        ``character_joints`` maps character joint -> the axes of its hinges (``("y","z","x")``).
        Passive joints may not be mapped: they are never driven, so a mapping would be silently
        ignored by physics and would only mislead the kinematic reference.
        """
        passive = set(passive)
        for cname, link in self.links.items():
            if cname not in character_joints:
                raise RecipeError(
                    f"joint map names unknown character joint '{cname}'; known: "
                    f"{', '.join(character_joints)}",
                    field=f"joint_map.{cname}",
                    plugin=plugin,
                )
            if cname in passive:
                raise RecipeError(
                    f"joint map drives passive joint '{cname}' (passive joints follow physics "
                    "only); remove it or make the joint active",
                    field=f"joint_map.{cname}",
                    plugin=plugin,
                )
            for h in link.human:
                if h not in human_joints:
                    raise RecipeError(
                        f"joint map entry '{cname}' names unknown human joint '{h}'; known: "
                        f"{', '.join(human_joints)}",
                        field=f"joint_map.{cname}.human",
                        plugin=plugin,
                    )
            n = len(character_joints[cname])
            if link.axes is not None and len(link.axes) != n:
                raise RecipeError(
                    f"joint map entry '{cname}' gives {len(link.axes)} axes but the character "
                    f"joint has {n} hinge(s) ({', '.join(character_joints[cname])})",
                    field=f"joint_map.{cname}.axes",
                    plugin=plugin,
                )
            if link.offset is not None and len(link.offset) != n:
                raise RecipeError(
                    f"joint map entry '{cname}' gives {len(link.offset)} offsets but the "
                    f"character joint has {n} hinge(s)",
                    field=f"joint_map.{cname}.offset",
                    plugin=plugin,
                )

    def hinge_angles(
        self, cname: str, hinge_axes: Sequence[str], local_rot: np.ndarray
    ) -> np.ndarray:
        """Angles ``(T, k)`` (radians) of character joint ``cname`` from composed human rotations.

        ``local_rot`` is ``(T, 4)`` wxyz: the composition of the link's human joints.
        """
        import numpy as np

        from retarget.geometry import rotations as rot
        link = self.links[cname]
        axes = link.axes if link.axes is not None else tuple(hinge_axes)
        signs = np.array([-1.0 if a.startswith("-") else 1.0 for a in axes])
        mat = rot.to_matrix(rot.normalize(local_rot))
        if link.bend is not None:
            # A hinge like the elbow: how far the bone bends, whatever axis the source put the
            # bend about (sources disagree on where upper-arm twist lives; the bend does not).
            b = _AXIS_INDEX[link.bend.lstrip("+-")]
            bend = np.arccos(np.clip(mat[..., b, b], -1.0, 1.0))
            out = np.zeros((*local_rot.shape[:-1], len(axes)))
            out[..., 0] = bend * signs[0] * link.scale
        else:
            bare = [a.lstrip("+-") for a in axes]
            out = euler_intrinsic(mat, bare) * signs * link.scale
        if link.offset is not None:
            out = out + np.deg2rad(np.asarray(link.offset))
        return out


def euler_intrinsic(mat: np.ndarray, axes: Sequence[str]) -> np.ndarray:
    """First ``len(axes)`` intrinsic Tait-Bryan angles of ``mat`` (``(..., 3, 3)``).

    ``axes`` (1-3 distinct of x/y/z) is completed with the missing axes in x, y, z order; with
    ``R = R_i(a) R_j(b) R_k(c)`` the angles are recovered in closed form. Batched, no loops.
    """
    import numpy as np
    order = [_AXIS_INDEX[a] for a in axes]
    order += [i for i in range(3) if i not in order]
    i, j, k = order
    parity = 1.0 if (i, j, k) in ((0, 1, 2), (1, 2, 0), (2, 0, 1)) else -1.0
    r = np.asarray(mat)
    b = np.arcsin(np.clip(parity * r[..., i, k], -1.0, 1.0))
    a = np.arctan2(-parity * r[..., j, k], r[..., k, k])
    c = np.arctan2(-parity * r[..., i, j], r[..., i, i])
    return np.stack([a, b, c], axis=-1)[..., : len(axes)]


def elbow_link(side: str, scale: float = 1.0, twist: bool = False) -> JointLink:
    """The usual elbow: a z hinge bending forward (negative for the left arm, whose bone is +y).

    ``twist=True`` for a character elbow with a second (forearm twist) hinge, left at 0.
    """
    flex = "-z" if side == "left" else "z"
    return JointLink(
        human=(f"{side}_elbow",), bend="y", axes=(flex, "y") if twist else (flex,), scale=scale
    )
