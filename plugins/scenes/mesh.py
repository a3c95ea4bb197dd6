"""``mesh``: a scanned or modelled scene from an OBJ, PLY or GLB file.

MuJoCo collides meshes through their convex hulls, so a room given as one mesh cannot be used
as is (its hull would fill the room). The file is turned into collision geometry in one of two
ways (``collision``):

* ``heightfield`` (default): the mesh's top surface is rasterised into a MuJoCo height field
  (a ray cast straight down per grid cell, ``resolution`` metres apart). It is 2.5D: floors,
  steps, seats and tables are exact to the grid; the space under a table is filled.
* ``hulls``: every connected piece becomes its own convex hull (right for furniture modelled
  as separate closed pieces, wrong for one concave piece). Flat pieces (a single quad) are
  given 2 cm of thickness downwards so they have a hull.

Either way the plane z = 0 is added below, ``height_at`` reads the rasterised top surface
(bilinear, 0 outside the mesh's footprint) and ``surface_points`` samples the mesh triangles,
area weighted. Meshes are expected in metres with +Z up (``y_up`` converts glTF's +Y up;
``scale`` and ``offset`` adjust units and placement). A scanned room is used as scanned: this
scene is not randomized. Without ``path`` the scene is the bare floor.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from pydantic import Field

import retarget
from retarget.errors import PluginError
from retarget.kinds import PluginConfig, Scene
from retarget.scene.floor import add_floor

if TYPE_CHECKING:
    import mujoco
    import numpy as np
    import torch

RAY_START = 100.0  # metres above the mesh top where the rasterising rays start


MAX_EXTENT = 1000.0
"""Widest mesh a scene takes, metres: anything larger is almost always a units mistake."""
MAX_GRID_POINTS = 2_000_000
"""Most height-grid samples a mesh is rasterised into (one ray each, once per scene)."""


class MeshConfig(PluginConfig):
    path: str | None = Field(None, description="OBJ, PLY or GLB file (None: the bare floor)")
    scale: float = Field(1.0, gt=0, description="multiplies every vertex (units to metres)")
    offset: tuple[float, float, float] = Field((0.0, 0.0, 0.0), description="added after scale")
    y_up: bool = Field(False, description="the file is +Y up (glTF): rotate it to +Z up")
    collision: Literal["heightfield", "hulls"] = "heightfield"
    resolution: float = Field(0.05, gt=0, description="height grid spacing, metres")


def load_mesh(cfg: MeshConfig):
    """The file as one triangle mesh in metres, +Z up; errors name the file."""
    import numpy as np
    import trimesh

    path = Path(cfg.path or "")
    try:
        mesh = trimesh.load(path, force="mesh")
    except Exception as exc:
        raise PluginError(f"cannot read mesh: {exc}", file=path, plugin="scene mesh") from exc
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise PluginError("the file holds no triangles", file=path, plugin="scene mesh")
    verts = np.asarray(mesh.vertices, dtype=float)
    if cfg.y_up:
        verts = verts[:, [0, 2, 1]] * np.array([1.0, -1.0, 1.0])
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is refused just below
        verts = verts * cfg.scale + np.asarray(cfg.offset)
    if not np.isfinite(verts).all():
        raise PluginError("the mesh has non-finite vertices", file=path, plugin="scene mesh")
    extent = float(np.ptp(verts, axis=0).max())
    if extent > MAX_EXTENT:
        raise PluginError(
            f"the mesh is {extent:.0f} m across (after scale {cfg.scale}); a scene is at most "
            f"{MAX_EXTENT:.0f} m",
            file=path, plugin="scene mesh", hint="check the units: scale: 0.01 for centimetres",
        )  # fmt: skip
    return trimesh.Trimesh(verts, np.asarray(mesh.faces), process=False)


def hull_safe(verts):
    """``verts`` plus, for a flat (coplanar) set, a copy moved 2 cm along the plane's normal
    (downwards when it has a vertical part): MuJoCo computes every mesh's convex hull and
    refuses a flat one, and a platform or a floor plate is a valid scene."""
    import numpy as np

    centred = verts - verts.mean(axis=0)
    _, s, vt = np.linalg.svd(centred, full_matrices=False)
    if len(s) == 3 and s[-1] > 1e-6 * max(s[0], 1e-12):
        return verts
    normal = vt[-1]
    if normal[2] > 0:
        normal = -normal
    return np.concatenate([verts, verts + 0.02 * normal])


class MeshScene(Scene[MeshConfig]):
    """A scene from a mesh file (OBJ/PLY/GLB) as a height field or convex pieces, on a floor."""

    name = "mesh"

    def __init__(self, config: PluginConfig | None = None) -> None:
        super().__init__(config)
        self._num_envs = 1
        self.mesh = load_mesh(self.config) if self.config.path else None
        self._grid = self._rasterise(self.mesh) if self.mesh is not None else None

    # ---------------------------------------------------------------- geometry

    def _rasterise(self, mesh: Any) -> dict[str, Any]:
        """Top-surface heights on a grid over the mesh's footprint (grid points at the
        corners of ``resolution`` cells, as MuJoCo's height field places its samples)."""
        import mujoco
        import numpy as np
        res = self.config.resolution
        lo, hi = mesh.bounds[0, :2], mesh.bounds[1, :2]
        ncol = max(int(np.ceil((hi[0] - lo[0]) / res)) + 1, 2)
        nrow = max(int(np.ceil((hi[1] - lo[1]) / res)) + 1, 2)
        if ncol * nrow > MAX_GRID_POINTS:
            raise PluginError(
                f"the height grid would have {ncol * nrow:,} points at resolution {res} m "
                f"(at most {MAX_GRID_POINTS:,})",
                file=self.config.path, plugin="scene mesh",
                hint="use a coarser resolution or a smaller mesh",
            )  # fmt: skip
        xs = lo[0] + np.arange(ncol) * res
        ys = lo[1] + np.arange(nrow) * res
        spec = mujoco.MjSpec()
        spec.add_mesh(
            name="m",
            uservert=hull_safe(mesh.vertices).ravel(),
            userface=mesh.faces.ravel(),
            inertia=mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL,  # a flat mesh has no volume
        )
        spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="m")
        model = spec.compile()
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        top = float(mesh.bounds[1, 2]) + RAY_START
        heights = np.zeros((nrow, ncol))
        geomid = np.zeros(1, dtype=np.int32)
        down = np.array([0.0, 0.0, -1.0])
        for r, y in enumerate(ys):  # preprocessing, once per scene: one ray per grid point
            for c, x in enumerate(xs):
                d = mujoco.mj_ray(model, data, np.array([x, y, top]), down, None, 1, -1, geomid)
                if d >= 0:
                    heights[r, c] = max(top - d, 0.0)
        return {"heights": heights, "x0": float(xs[0]), "y0": float(ys[0]), "res": res}

    def build(self, spec: mujoco.MjSpec) -> None:
        add_floor(spec)
        if self.mesh is None:
            return
        if self.config.collision == "heightfield" and self._grid is not None:
            self._add_heightfield(spec, self._grid)
        else:
            self._add_hulls(spec, self.mesh)

    def _add_heightfield(self, spec: mujoco.MjSpec, g: dict[str, Any]) -> None:
        import mujoco
        h = g["heights"]
        zmax = float(h.max())
        if zmax <= 0:
            return  # everything at floor level: the plane already is the floor
        nrow, ncol = h.shape
        half_x, half_y = (ncol - 1) * g["res"] / 2, (nrow - 1) * g["res"] / 2
        spec.add_hfield(
            name="scene_mesh_hfield",
            size=[half_x, half_y, zmax, 0.05],
            nrow=nrow,
            ncol=ncol,
            userdata=(h / zmax).ravel().tolist(),
        )
        spec.worldbody.add_geom(
            name="scene_mesh",
            type=mujoco.mjtGeom.mjGEOM_HFIELD,
            hfieldname="scene_mesh_hfield",
            pos=[g["x0"] + half_x, g["y0"] + half_y, 0.0],
            contype=1,
            conaffinity=1,
            rgba=[0.6, 0.6, 0.65, 1.0],
        )

    def _add_hulls(self, spec: mujoco.MjSpec, mesh: Any) -> None:
        import mujoco
        import numpy as np
        for k, piece in enumerate(mesh.split(only_watertight=False)):
            verts = np.asarray(piece.vertices, dtype=float)
            if len(verts) < 3:
                continue
            verts = hull_safe(verts)
            spec.add_mesh(name=f"scene_mesh_{k}", uservert=verts.ravel())
            spec.worldbody.add_geom(
                name=f"scene_mesh_{k}",
                type=mujoco.mjtGeom.mjGEOM_MESH,
                meshname=f"scene_mesh_{k}",
                contype=1,
                conaffinity=1,
                rgba=[0.6, 0.6, 0.65, 1.0],
            )

    # ---------------------------------------------------------------- queries

    def allocate(self, num_envs: int) -> None:
        self._num_envs = num_envs

    def height_at(self, xy: torch.Tensor) -> torch.Tensor:
        import torch
        if self._grid is None:
            return torch.zeros(xy.shape[:-1], dtype=torch.float32)
        g = self._grid
        h = torch.as_tensor(g["heights"], dtype=torch.float64)
        nrow, ncol = h.shape
        u = (xy[..., 0].double() - g["x0"]) / g["res"]
        v = (xy[..., 1].double() - g["y0"]) / g["res"]
        inside = (u >= 0) & (u <= ncol - 1) & (v >= 0) & (v <= nrow - 1)
        u = u.clamp(0, ncol - 1)
        v = v.clamp(0, nrow - 1)
        c0 = u.floor().long().clamp(max=ncol - 2)
        r0 = v.floor().long().clamp(max=nrow - 2)
        fu, fv = u - c0, v - r0
        flat = h.reshape(-1)

        def at(r: torch.Tensor, c: torch.Tensor) -> torch.Tensor:
            return flat[r * ncol + c]

        top = at(r0, c0) * (1 - fu) + at(r0, c0 + 1) * fu
        bottom = at(r0 + 1, c0) * (1 - fu) + at(r0 + 1, c0 + 1) * fu
        out = top * (1 - fv) + bottom * fv
        return torch.where(inside, out, torch.zeros_like(out)).float()

    def surface_points(self, count: int, rng: np.random.Generator) -> np.ndarray:
        import numpy as np
        if self.mesh is None:
            pts = np.zeros((count, 3))
            pts[:, :2] = rng.uniform(-2.0, 2.0, size=(count, 2))
        else:
            tri = np.asarray(self.mesh.triangles)
            area = np.asarray(self.mesh.area_faces)
            pick = rng.choice(len(tri), size=count, p=area / area.sum())
            a, b = rng.uniform(size=(2, count, 1))
            flip = (a + b) > 1
            a, b = np.where(flip, 1 - a, a), np.where(flip, 1 - b, b)
            t = tri[pick]
            pts = t[:, 0] + a * (t[:, 1] - t[:, 0]) + b * (t[:, 2] - t[:, 0])
        return np.broadcast_to(pts, (self._num_envs, count, 3)).copy()


@retarget.hookimpl
def register_scenes(register) -> None:
    register(MeshScene)
