"""``motions.mirror`` in a recipe: the training library holds each clip twice, once left
and right swapped (``retarget.motion.mirror``), and clips given to evaluate stay as they are."""

from __future__ import annotations

from helpers import TINY

from retarget.motion.procedural import default_motions


def test_a_recipe_adds_mirrored_clips_only_when_it_asks(tmp_path) -> None:
    """``motions.mirror``: each clip once more, left and right swapped,
    drawn as often as its original; clips given at evaluation (``--motions``) stay as they are."""
    import torch

    from retarget.env.build import env_from_recipe
    from retarget.motion.bvh_write import write_bvh
    from retarget.recipe import parse_text, resolve
    from retarget.registry.loader import load_plugins

    registry = load_plugins()
    text = TINY + "motions: {mirror: true, weights: {'walk*': 3}}\n"
    resolved = resolve(parse_text(text, "tiny.yaml", ".yaml"), registry)
    env = env_from_recipe(resolved, num_envs=2, threads=1, registry=registry)
    names, lib = env.library.names, env.library
    half = len(names) // 2
    assert len(names) == 2 * half and names[half:] == [f"{n}_mirrored" for n in names[:half]]
    walk, flipped, idle = (names.index(n) for n in ("walk", "walk_mirrored", "idle"))
    assert float(lib.weights[flipped]) == float(lib.weights[walk]) > float(lib.weights[idle])
    # the mirrored walk's root takes the original's path with y negated
    a, b, n = int(lib.start[walk]), int(lib.start[flipped]), int(lib.length[walk])
    flip = torch.tensor([1.0, -1.0, 1.0])
    assert torch.allclose(lib.root_pos[b : b + n], lib.root_pos[a : a + n] * flip, atol=1e-5)
    walk_clip = next(c for c in default_motions() if c.name == "walk")
    write_bvh(walk_clip, tmp_path / "walk.bvh")
    given = env_from_recipe(resolved, num_envs=2, threads=1, registry=registry,
                            motions=str(tmp_path))  # fmt: skip
    assert given.library.names == ["walk"]
