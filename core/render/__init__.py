"""Offscreen pictures and videos: characters at rest, motion clips as skeletons, policy rollouts.

Every renderer here starts through :func:`retarget.render.gl.ensure_offscreen`, the one place
that chooses MuJoCo's OpenGL backend.
"""
