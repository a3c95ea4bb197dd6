"""A MuJoCo world drawn in the browser: every geom as a viser mesh, moved from body poses.

viser (the viewer mjlab uses) serves a three.js page and keeps it in sync with Python over a
WebSocket; this module only turns a compiled model's geoms into meshes once (boxes, spheres,
capsules, cylinders, ellipsoids, meshes; planes become the grid) and then moves the handles of
the moving ones each frame: from an ``MjData`` after kinematics, or from the body poses a live
server sends. A human reference (the ghost skeleton) and the devices are line segments and
small boxes beside it.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from retarget.motion import skeleton as sk

GHOST = (70, 120, 240)
DEVICE = (255, 215, 30)


def _mesh(model: mujoco.MjModel, g: int):
    """The geom as a trimesh in its own frame, or None for planes (drawn as the grid)."""
    import trimesh

    kind, size = int(model.geom_type[g]), model.geom_size[g]
    t = mujoco.mjtGeom
    if kind == t.mjGEOM_BOX:
        return trimesh.creation.box(extents=2 * size)
    if kind == t.mjGEOM_SPHERE:
        return trimesh.creation.icosphere(subdivisions=2, radius=float(size[0]))
    if kind == t.mjGEOM_CAPSULE:
        r, h = float(size[0]), 2 * float(size[1])
        return trimesh.creation.capsule(height=h, radius=r, count=[8, 8])
    if kind == t.mjGEOM_CYLINDER:
        r, h = float(size[0]), 2 * float(size[1])
        return trimesh.creation.cylinder(radius=r, height=h, sections=16)
    if kind == t.mjGEOM_ELLIPSOID:
        mesh = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        mesh.apply_scale(size)
        return mesh
    if kind == t.mjGEOM_MESH:
        m = int(model.geom_dataid[g])
        a, n = int(model.mesh_vertadr[m]), int(model.mesh_vertnum[m])
        fa, fn = int(model.mesh_faceadr[m]), int(model.mesh_facenum[m])
        return trimesh.Trimesh(model.mesh_vert[a : a + n].copy(),
                               model.mesh_face[fa : fa + fn].copy(), process=False)  # fmt: skip
    return None


def _rgb(model: mujoco.MjModel, g: int) -> tuple[int, int, int]:
    rgba = model.geom_rgba[g]
    if int(model.geom_matid[g]) >= 0:
        rgba = model.mat_rgba[int(model.geom_matid[g])]
    return tuple(int(255 * float(c)) for c in rgba[:3])  # type: ignore[return-value]


@dataclass
class _Geom:
    index: int
    body: int
    handle: object


class BrowserScene:
    """The geoms of ``model`` under ``prefix`` in a viser scene."""

    def __init__(self, server, model: mujoco.MjModel, prefix: str = "/world") -> None:
        self.server, self.model, self.prefix = server, model, prefix
        self.geoms: list[_Geom] = []
        server.scene.add_grid(f"{prefix}/floor", width=20.0, height=20.0, cell_size=0.5,
                              plane="xy")  # fmt: skip
        data = mujoco.MjData(model)
        mujoco.mj_kinematics(model, data)
        for g in range(model.ngeom):
            if model.geom_rgba[g, 3] == 0 or int(model.geom_group[g]) > 2:
                continue  # invisible or collision-only geoms
            mesh = _mesh(model, g)
            if mesh is None:
                continue
            handle = server.scene.add_mesh_simple(
                f"{prefix}/geom{g}", np.asarray(mesh.vertices, np.float32),
                np.asarray(mesh.faces, np.uint32), color=_rgb(model, g),
                flat_shading=False, cast_shadow=False, receive_shadow=False,
            )  # fmt: skip
            self.geoms.append(_Geom(g, int(model.geom_bodyid[g]), handle))
        self.show(data)

    def set_visible(self, visible: bool) -> None:
        """Show or hide every geom (the world's props and characters)."""
        with self.server.atomic():
            for geom in self.geoms:
                geom.handle.visible = visible

    def show(self, data: mujoco.MjData) -> None:
        """Move every geom to where ``data`` (after kinematics) has it."""
        with self.server.atomic():
            for geom in self.geoms:
                quat = np.empty(4)
                mujoco.mju_mat2Quat(quat, data.geom_xmat[geom.index])
                geom.handle.position = data.geom_xpos[geom.index].copy()
                geom.handle.wxyz = quat

    def show_bodies(self, ids: np.ndarray, pos: np.ndarray, quat: np.ndarray) -> None:
        """Move the geoms of bodies ``ids`` to body poses ``pos`` ``(B, 3)``, ``quat``
        ``(B, 4)`` (what a live server sends); other geoms stay."""
        from retarget.geometry import rotations as rot

        where = {int(b): k for k, b in enumerate(ids)}
        with self.server.atomic():
            for geom in self.geoms:
                k = where.get(geom.body)
                if k is None:
                    continue
                local_pos = self.model.geom_pos[geom.index]
                local_quat = self.model.geom_quat[geom.index]
                geom.handle.position = pos[k] + rot.apply(quat[k], local_pos)
                geom.handle.wxyz = rot.mul(quat[k], local_quat)



def draw_ghost(server, joints: np.ndarray, devices: np.ndarray | None = None,
               prefix: str = "/world") -> None:  # fmt: skip
    """The human reference skeleton ``(J, 3)`` as lines and the devices ``(3, 7)`` as boxes
    (re-adding a node under the same name replaces it)."""
    scene = server.scene
    segments = np.stack([joints[list(sk.PARENTS[1:])], joints[1:]], axis=1).astype(np.float32)
    scene.add_line_segments(f"{prefix}/ghost", segments, colors=GHOST, thickness=4.0,
                             thickness_units="screen")
    for d in range(0 if devices is None else len(devices)):
        assert devices is not None
        scene.add_box(f"{prefix}/device{d}", color=DEVICE, dimensions=(0.06, 0.06, 0.06),
                      position=devices[d, :3], wxyz=devices[d, 3:])  # fmt: skip
