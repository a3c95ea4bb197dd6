"""Choosing MuJoCo's OpenGL backend: the one place retarget touches ``MUJOCO_GL``.

Offscreen rendering on a machine without a display needs OSMesa (CPU) or EGL (GPU). MuJoCo
picks its backend from ``MUJOCO_GL`` when its rendering module is first imported, which in a
long process (a test session, a command that also trains) may have happened already, so the
choice is made here, right before a renderer is built, rather than at import time.
"""

from __future__ import annotations

import os

from retarget.errors import RetargetError


def ensure_offscreen() -> None:
    """Switch MuJoCo's renderer to OSMesa when there is no display and GLFW was picked.

    MuJoCo reads ``MUJOCO_GL`` once, when ``mujoco`` is first imported; in a process where
    something imported it before this module (a test session, a plugin), the GLFW backend it
    picked aborts without a display. The renderer looks its context class up at construction,
    so pointing it at OSMesa here is enough.
    """
    if os.environ.get("DISPLAY"):
        return
    os.environ.setdefault("MUJOCO_GL", "osmesa")  # read when MuJoCo's GL module first loads
    if os.environ["MUJOCO_GL"].lower() == "egl":
        return
    from mujoco.rendering.classic import gl_context

    current = getattr(gl_context, "GLContext", None)
    if current is None or "osmesa" in getattr(current, "__module__", ""):
        return
    try:
        from mujoco.osmesa import GLContext
    except ImportError as exc:  # pragma: no cover - depends on system libraries
        raise RetargetError(
            "offscreen rendering needs OSMesa (apt-get install libosmesa6) "
            "or MUJOCO_GL=egl with a GPU"
        ) from exc
    gl_context.GLContext = GLContext
