"""A tracking expert that needs no training: trajectory optimisation over a reference clip.

:class:`~retarget.expert.beam.BeamTracker` plans PD-target actions in the env's own action
space with the simulator itself (a sampling beam search over the reference, SAMCON-style);
:class:`~retarget.expert.ilqr.IlqrRefiner` improves such a path with the dynamics'
derivatives (iLQR); the built-in planners (``retarget plugins``) use them;
:mod:`retarget.expert.store` writes what it found per clip (states, actions, the beam's
alternative segments and a report) so that policies learn from it by supervised learning
(``retarget train --expert DIR``). ``retarget expert`` runs it over clips, folders and
archives, in parallel and resumably.
"""

from typing import TYPE_CHECKING

from retarget.lazy import lazy_exports

if TYPE_CHECKING:
    from retarget.expert.beam import BeamTracker
    from retarget.expert.config import ExpertConfig, IlqrConfig
    from retarget.expert.ilqr import IlqrRefiner
    from retarget.kinds.track import Track

__getattr__ = lazy_exports(
    __name__,
    {
        "BeamTracker": "retarget.expert.beam",
        "ExpertConfig": "retarget.expert.config",
        "IlqrConfig": "retarget.expert.config",
        "IlqrRefiner": "retarget.expert.ilqr",
        "Track": "retarget.kinds.track",
    },
)

__all__ = ["BeamTracker", "ExpertConfig", "IlqrConfig", "IlqrRefiner", "Track"]
