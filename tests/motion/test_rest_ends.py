"""Starts from and stops to a standstill made from clips cut mid-stride
(``retarget.motion.rest_ends``): the held pose is a double-support frame of the take, the
speed ramps from 0 to the take's own, and every frame is a pose of the take."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import TINY

from retarget.motion.procedural import default_motions
from retarget.motion.rest_ends import RestEnds, rest_ends, root_speed, warp_profile


@pytest.fixture(scope="module")
def moving():
    """The generated walk without its own start and stop: moving at both ends."""
    walk = next(c for c in default_motions() if c.name == "walk")
    fps = walk.fps
    return walk.slice(int(2.0 * fps), walk.num_frames - int(1.5 * fps))


def test_the_profile_holds_then_ramps_to_the_takes_own_speed() -> None:
    ends = RestEnds(hold=0.5, ramp=1.0, keep=2.0)
    p = warp_profile(30.0, ends)
    rate = np.diff(p) * 30.0  # seconds of the take per second
    assert np.all(p[:15] == 0.0)  # held still for half a second
    assert np.all(np.diff(p) >= 0) and np.allclose(rate[-30:], 1.0)
    assert p[-1] == pytest.approx(ends.ramp / 2 + ends.keep, abs=1e-9)


def test_a_moving_clip_gets_a_start_and_a_stop(moving) -> None:
    assert root_speed(moving)[:20].mean() > 0.8 and root_speed(moving)[-20:].mean() > 0.8
    made = {c.meta["rest_end"]: c for c in rest_ends(moving)}
    assert set(made) == {"from_rest", "to_rest"}
    start, stop = made["from_rest"], made["to_rest"]
    assert start.name == f"{moving.name}_from_rest" and start.fps == moving.fps
    hold = int(0.5 * moving.fps)
    for clip, still in ((start, slice(0, hold)), (stop, slice(-hold, None))):
        speed = root_speed(clip)
        assert speed[still].max() < 1e-6  # standing still, on both feet
        assert clip.contacts[still].all()
        assert np.ptp(clip.global_pos[still], axis=0).max() < 1e-9
    # sets off: the speed ramps from 0 to the take's own over the ramp second
    s = root_speed(start)
    assert s[hold + 3] < 0.3 < 0.8 < np.mean(s[-10:])
    # every frame of the start after the ramp is the take itself, only shifted in time
    tail = start.global_pos[-5:]
    dists = [np.abs(moving.global_pos[i:i + 5] - tail).max()
             for i in range(moving.num_frames - 4)]
    assert min(dists) < 1e-6, "the start's last frames are not frames of the take"


def test_clips_that_do_not_move_or_never_stand_get_nothing(moving) -> None:
    idle = next(c for c in default_motions() if c.name == "idle")
    assert rest_ends(idle) == []
    airborne = moving.with_(contacts=np.zeros_like(moving.contacts))  # a run's flight phases
    assert rest_ends(airborne) == []
    assert rest_ends(moving.slice(0, 10)) == []  # too short to look for a stance


def test_bad_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="ramp"):
        RestEnds(ramp=0.0)
    with pytest.raises(ValueError, match="hold"):
        RestEnds(hold=1e9)


def test_a_recipe_trains_on_them_only_when_it_asks(moving) -> None:
    from retarget.env.build import env_from_recipe
    from retarget.recipe import parse_text, resolve
    from retarget.registry.loader import load_plugins

    registry = load_plugins()
    names = {}
    for flag in (False, True):
        text = TINY + f"motions: {{rest_ends: {str(flag).lower()}}}\n"
        resolved = resolve(parse_text(text, "tiny.yaml", ".yaml"), registry)
        env = env_from_recipe(resolved, num_envs=2, threads=1, registry=registry)
        names[flag] = env.library.names
    assert not any(n.endswith("_rest") for n in names[False])
    added = [n for n in names[True] if n.endswith(("_from_rest", "_to_rest"))]
    assert names[True][: len(names[False])] == names[False] and added
    assert len(names[True]) == len(names[False]) + len(added)
