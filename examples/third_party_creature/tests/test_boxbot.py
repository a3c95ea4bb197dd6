"""The package's own contract tests: retarget's kit, run on both plugins."""

from retarget_boxbot.character import Boxbot
from retarget_boxbot.sensor import HeadVelocity

from retarget.testing import parametrize_with_checks


@parametrize_with_checks([Boxbot, HeadVelocity])
def test_contract(plugin, check):
    check(plugin)
