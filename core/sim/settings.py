"""The recipe's ``sim`` section, defined with the other settings schemas in
:mod:`retarget.settings.sim` (the recipe layer reads them without importing the simulator)."""

from retarget.settings.sim import ACTUATIONS, Actuation, Backend, SimSettings

__all__ = ["ACTUATIONS", "Actuation", "Backend", "SimSettings"]
