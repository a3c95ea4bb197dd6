"""A reward whose module reaches into retarget's internals: the toolkit check must refuse it."""

from __future__ import annotations

import contract_doubles as d

from retarget.env.managers import RewardManager  # not a toolkit module


class Internal(d.GoodReward):
    """Imports the env's reward manager, which plugins must not rely on."""

    name = "internal"
    manager = RewardManager
