"""The planner's settings (``retarget expert --set planner.FIELD=VALUE``)."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field

from retarget.kinds.base import PluginConfig

ADDED_LATER: dict[str, object] = {
    "inverse_ff": 0.0, "inverse_support": False, "lookahead_share": 1.0,
}
"""Planner fields added after expert directories were written, with the value that plans as
before: a field at that value is left out of a directory's settings key, so a directory
planned before the field existed still resumes."""

BEAM_IN_ILQR_ADDED_LATER: dict[str, object] = {"lookahead_share": 1.0}
"""The beam search's fields added after ``beam_ilqr`` directories were written (that
planner records the beam's settings under ``beam``), with the value that plans as before."""

ILQR_ADDED_LATER: dict[str, object] = {"relinearise": 1}
"""The same for the refinement's fields (``beam_ilqr``'s ``ilqr`` settings): a directory
refined before chord rounds existed recorded no ``relinearise`` and refined as with 1."""


class CostWeights(BaseModel):
    """Weights of the segment-end cost, each term a distance to the reference frame."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    body: float = Field(10.0, ge=0, description="mean world distance of the bodies (m)")
    orientation: float = Field(5.0, ge=0, description="root orientation, 1 - cos^2(angle/2)")
    joints: float = Field(2.0, ge=0, description="mean squared joint-angle error (rad^2)")
    height: float = Field(5.0, ge=0, description="squared root-height error (m^2) x 10")
    velocity: float = Field(0.05, ge=0, description="mean squared qvel error")
    effort: float = Field(0.0, ge=0, description="mean squared offset from the nominal "
                          "targets (action units): prefers the quietest plan that tracks")
    pose: float = Field(0.0, ge=0, description="mean root-relative distance of the bodies (m)")


class Rescue(BaseModel):
    """A second try at a segment whose best sample ends its lookahead far from the reference.

    Settings that keep the pose tight (little noise, a pose term, a running cost) track walks
    closest but lose runs, where a longer lookahead and plain costs keep the character up; a
    rescue plans only the segments in trouble the robust way, so one planner has both."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    threshold: float = Field(0.0, ge=0, le=10, description="mean world distance of the "
                             "bodies (m) of the best sample at the end of its lookahead above "
                             "which the segment is planned again; 0 turns rescues off")
    lookahead: int = Field(12, ge=0, le=72, description="the rescue's lookahead")
    sigma: float = Field(0.2, ge=0, le=2, description="the rescue's offset noise")
    pose: float = Field(0.0, ge=0, description="the rescue's weights.pose")
    running: float = Field(0.0, ge=0, le=100, description="the rescue's running weight")


class ExpertConfig(PluginConfig):
    """Beam-search tracking over PD targets; the defaults were chosen on training-style walks
    (``benchmarks/results/expert_*.md`` has the comparisons)."""

    samples: int = Field(512, ge=2, le=65_536, description="rollouts per segment")
    beam: int = Field(64, ge=1, le=4096, description="states kept after each segment")
    segment: int = Field(3, ge=1, le=36, description="control steps per segment")
    sigma: float = Field(0.2, ge=0, le=2, description="offset noise (action units) of the "
                         "strongest joint; weaker joints get less (strength_power)")
    strength_power: float = Field(1.0, ge=0, le=4, description="noise of a joint scales as "
                                  "(its torque limit / the largest)^power")
    carry: float = Field(0.8, ge=0, lt=1, description="share of the parent's offset a "
                         "sample keeps (correlated offsets over segments)")
    lookahead: int = Field(6, ge=0, le=72, description="control steps each sample is "
                           "continued past its segment (same offset) before it is scored: a "
                           "state that is about to fall scores badly before it falls")
    lookahead_share: float = Field(0.25, gt=0, le=1, description="share of the samples "
                                   "continued through the lookahead: those with the lowest "
                                   "cost at their segment's end (never fewer than `beam`); "
                                   "the rest are dropped unscored. The lookahead is most of a "
                                   "segment's simulation, so 0.25 halves it (1: every sample, "
                                   "as directories planned before it existed)")
    quiet: float = Field(0.0, ge=0, le=1, description="share of samples that add no new "
                         "noise to their parent's (decayed) offset")
    gain: float = Field(1.0, ge=0, le=10, description="feedback added to every action: gain "
                        "x (reference angle - current angle), in action units")
    velocity_ff: float = Field(1.0, ge=0, le=2, description="share of the servo's damping "
                               "lag cancelled: the nominal target gains damping x the "
                               "reference joint velocity (kd/kp x qdot)")
    inverse_ff: float = Field(0.0, ge=0, le=2, description="share of the reference's "
                              "inverse-dynamics torque (over kp) added to the nominal target "
                              "of every joint whose bodies touch nothing in that frame "
                              "(arms, head, a swing leg): servos no longer sag or lag there")
    inverse_support: bool = Field(False, description="joints whose bodies touch the world "
                                  "get inverse torques too, the root's share carried by "
                                  "least-norm forces at the contacts (a stance leg's load)")
    lead: int = Field(1, ge=0, le=10, description="the nominal targets are this many frames "
                      "ahead of the frame being reached (PD servos lag)")
    keep: int = Field(16, ge=0, le=4096, description="beam members per segment saved as "
                      "extra demonstrations (states around the best path)")
    running: float = Field(0.0, ge=0, le=100, description="weight of the mean cost over the "
                           "segment's own steps, added to the cost scored after the lookahead "
                           "(keeps the pose on the reference between segment ends)")
    passes: int = Field(1, ge=1, le=8, description="search passes; each later pass samples "
                        "around the previous pass's best offsets with refine x sigma "
                        "(SAMCON's iterations) and the lowest-cost path is kept")
    refine: float = Field(0.5, gt=0, le=1, description="noise of a refinement pass, as a "
                          "share of sigma")
    seed: int = Field(0, ge=0)
    weights: CostWeights = Field(default_factory=CostWeights)
    rescue: Rescue = Field(default_factory=Rescue)


class IlqrWeights(PluginConfig):
    """Weights of the squared tracking cost every reached frame pays (Gauss-Newton)."""

    body: float = Field(100.0, ge=0, description="mean squared world distance of the bodies (m^2)")
    pose: float = Field(100.0, ge=0, description="mean squared root-relative distance of the "
                        "bodies (m^2): the pose, which MPJPE measures")
    joints: float = Field(1.0, ge=0, description="mean squared joint-angle error (rad^2)")
    velocity: float = Field(0.01, ge=0, description="mean squared qvel error")
    effort: float = Field(0.1, ge=0, description="mean squared change from the starting "
                          "path's actions (action units): keeps the refinement local")


class IlqrConfig(PluginConfig):
    """Settings of the refinement (``retarget expert --method beam_ilqr --planner ilqr.X=``)."""

    iterations: int = Field(6, ge=0, le=200, description="backward / forward rounds per window "
                            "(per path without windows); a round after a kept one linearises "
                            "the new path first (most of the cost) unless it is a chord step "
                            "(`relinearise`)")
    eps: float = Field(1e-6, gt=0, le=1e-2, description="finite-difference step")
    regularization: float = Field(100.0, gt=0, le=1e6, description="first damping added to "
                                  "the action Hessian; x10 after a failed round, /3 after a "
                                  "kept one")
    alphas: tuple[float, ...] = Field((1.0, 0.5, 0.25, 0.1, 0.03), min_length=1, max_length=16,
                                      description="line-search step sizes, rolled out together")
    feedback: tuple[float, ...] = Field((1.0, 0.0), min_length=1, max_length=4,
                                        description="shares of the feedback gains the line "
                                        "search tries with every step size (0: the step "
                                        "open loop, which holds where the gains of a poor "
                                        "linear model would push the rollout away)")
    window: int = Field(18, ge=0, le=720, description="control steps optimised together; "
                        "0: the whole path at once. A window is optimised from the refined "
                        "path's state at its start, its first `commit` steps kept, the rest "
                        "of the path re-rolled from there (a shorter linear model holds better)")
    commit: int = Field(6, ge=1, le=720, description="steps kept from each window")
    threshold: float = Field(0.5, gt=0, le=10, description="PHC's failure distance (mean "
                             "body error, m): a refined path that exceeds it at any frame "
                             "where the given path did not is dropped for the given one")
    chunk: int = Field(4, ge=1, le=64, description="control steps linearised per batch "
                       "(memory: chunk x (1 + 2 nv + nu) simulations)")
    relinearise: int = Field(2, ge=1, le=100, description="linearise the path again after "
                             "every N-th kept round; in between, a chord step: the dynamics' "
                             "and the cost's derivatives are kept and only the residuals are "
                             "taken from the new path's rollout (a round then costs its line "
                             "search alone, a tenth of a linearisation)")
    weights: IlqrWeights = Field(default_factory=IlqrWeights)
