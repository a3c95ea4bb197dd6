"""Boxes from a mesh: each connected piece of an OBJ/PLY/GLB as an upright oriented box.

Scenes recorded with a capture (the box-climb sequences' ``multi_boxes.obj``) often give
their furniture as one mesh of closed boxes. A box prop is described by its footprint
(centre, yaw, extents: the smallest rectangle around the piece's vertices seen from above,
by rotating calipers over the convex hull's edges) and its top height; its bottom is taken
to stand on the floor. Pieces that are not boxes (a slanted or hollow shape) are still
bounded by such a box, which is then an approximation the result reports (``fill``: the
piece's volume over the box's, 1 for a box).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from retarget.errors import PluginError

MAX_PIECES = 64
"""Most boxes read from one mesh (furniture, not a scanned room: use the ``mesh`` scene)."""


@dataclass(frozen=True)
class MeshBox:
    position: tuple[float, float]  # footprint centre, metres
    yaw: float  # radians
    size: tuple[float, float]  # footprint extents along its own x, y
    height: float  # top above the floor
    fill: float  # piece volume / box volume


def _hull(xy: np.ndarray) -> np.ndarray:
    """Convex hull of 2-D points, counter-clockwise (Andrew's monotone chain: a few dozen
    vertices per piece, so a dependency for it would be the heavier choice)."""
    pts = sorted({(float(x), float(y)) for x, y in xy})
    if len(pts) < 3:
        return np.array(pts)

    def half(points):
        out: list[tuple[float, float]] = []
        for p in points:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def _footprint(xy: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """Centre, yaw and extents of the minimum-area rectangle around 2-D points."""
    hull = _hull(xy)
    best = None
    for a, b in zip(hull, np.roll(hull, -1, axis=0), strict=True):
        edge = b - a
        if np.linalg.norm(edge) < 1e-9:
            continue
        yaw = float(np.arctan2(edge[1], edge[0]))
        c, s = np.cos(yaw), np.sin(yaw)
        local = xy @ np.array([[c, -s], [s, c]])
        lo, hi = local.min(0), local.max(0)
        area = float(np.prod(hi - lo))
        if best is None or area < best[0]:
            centre = np.array([[c, -s], [s, c]]) @ ((lo + hi) / 2)
            best = (area, centre, yaw, hi - lo)
    if best is None:
        raise ValueError("degenerate footprint")
    _, centre, yaw, size = best
    yaw = (yaw + np.pi / 4) % (np.pi / 2) - np.pi / 4  # the same rectangle, smallest turn
    if abs(((best[2] - yaw) % np.pi) - np.pi / 2) < 1e-6:
        size = size[::-1]
    return centre, yaw, size


def boxes_from_mesh(path: str | Path) -> list[MeshBox]:
    """The upright boxes of a mesh file (metres, +Z up); errors name the file."""
    import trimesh

    path = Path(path)
    try:
        mesh = trimesh.load(str(path), force="mesh")
    except Exception as exc:  # trimesh raises many types for bad files
        raise PluginError(f"cannot read the mesh: {exc}", file=path) from None
    pieces = mesh.split(only_watertight=False) if len(mesh.faces) else []
    if not len(pieces):
        raise PluginError("the mesh has no faces", file=path)
    if len(pieces) > MAX_PIECES:
        raise PluginError(f"{len(pieces)} pieces; at most {MAX_PIECES} boxes are read",
                          file=path, hint="use the mesh scene for a scanned room")  # fmt: skip
    out = []
    for piece in pieces:
        v = np.asarray(piece.vertices, dtype=np.float64)
        top = float(v[:, 2].max())
        if top <= 0.01:
            continue  # a floor patch, not a box
        centre, yaw, size = _footprint(v[:, :2])
        volume = float(abs(piece.volume)) if piece.is_watertight else float("nan")
        fill = volume / max(float(np.prod(size)) * top, 1e-12)
        out.append(MeshBox((float(centre[0]), float(centre[1])), float(yaw),
                           (float(size[0]), float(size[1])), top, fill))  # fmt: skip
    return out


MESH_SUFFIXES = (".obj", ".ply", ".glb")


def mesh_beside(source: Path) -> Path | None:
    """The one scene mesh in a clip file's folder (the box-climb layout: a sequence's
    ``multi_boxes.obj`` next to its joint positions), or None; several is an error."""
    found = sorted(p for p in source.parent.iterdir() if p.suffix.lower() in MESH_SUFFIXES)
    if len(found) > 1:
        raise PluginError(
            f"several scene meshes beside the clip ({', '.join(p.name for p in found)})",
            file=source, hint="keep one per clip folder",
        )  # fmt: skip
    return found[0] if found else None
