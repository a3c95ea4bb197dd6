"""The recipe's ``env`` section, defined with the other settings schemas in
:mod:`retarget.settings.env` (the recipe layer reads them without importing the env)."""

from retarget.settings.env import CurriculumOptions, EnvOptions, RootAssistOptions

__all__ = ["CurriculumOptions", "EnvOptions", "RootAssistOptions"]
