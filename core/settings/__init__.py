"""The settings schemas a recipe holds that are not plugins (``env``, ``sim``).

Plain pydantic models with no behaviour, so the recipe layer validates a recipe without
importing the environment or the simulator; those layers read the same models."""
