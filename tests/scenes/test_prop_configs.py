"""Prop-scene configs derive from one base: the scene reads density, randomization and (for
scenes placed as a whole) position and yaw as typed fields, and a scene whose config does not
derive from the base is refused naming it."""

from __future__ import annotations

import pytest

from retarget import PluginConfig, PluginError
from retarget.plugins.scenes.path_boxes import PathBoxesConfig
from retarget.plugins.scenes.stool import Stool
from retarget.scene.props import PropSceneConfig, PropSetConfig


def test_placed_and_self_placing_scene_configs_share_the_base() -> None:
    assert issubclass(PropSceneConfig, PropSetConfig)
    assert issubclass(PathBoxesConfig, PropSetConfig)
    assert not issubclass(PathBoxesConfig, PropSceneConfig)  # it places its own boxes
    stool = Stool(Stool.Config(position=(2.0, -1.0), yaw=0.0, density=800.0))
    (prop,) = stool.placed_props()
    assert prop.xy == pytest.approx((2.0, -1.0)) and stool.config.density == 800.0


def test_a_prop_scene_with_a_foreign_config_is_refused() -> None:
    class Loose(PluginConfig):
        size: float = 1.0

    class Odd(Stool):
        """A stool whose config forgot the prop-scene base."""

        name = "odd_stool"
        Config = Loose

    with pytest.raises(PluginError, match=r"odd_stool.*PropSetConfig"):
        Odd()
