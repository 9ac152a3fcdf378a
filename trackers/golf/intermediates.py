"""Everything one golf step computed, one small record per stage (hashed into the replay digest)."""

from __future__ import annotations

from dataclasses import dataclass, field

from trackreplay.trackers.golf.blobs import GatedBlobs
from trackreplay.trackers.golf.calibration import RowEvidence
from trackreplay.trackers.golf.landing import EkfState
from trackreplay.trackers.golf.particles import ParticleSet
from trackreplay.trackers.golf.reinit import Reinit
from trackreplay.trackers.golf.search_region import SearchRegion
from trackreplay.trackers.golf.silhouette import LutSilhouette
from trackreplay.trackers.golf.trail import TrailPoints
from trackreplay.trackers.golf.validate import Validation


@dataclass(frozen=True, eq=False)
class GolfIntermediates:
    """The stages in pipeline order; ``mode`` is "ptz" (camera pose known), "image" (no encoders)
    or "idle" (not started: every stage empty)."""

    mode: str
    reinit: Reinit  # §2.3: where the samples started again this frame ("" kind: they did not)
    search: SearchRegion  # §2.1 I_s from the predicted samples (§2.2)
    silhouette: LutSilhouette  # §2.1 LUT switch and I_c
    blobs: GatedBlobs  # §2.1 blob gating and the ball
    particles: ParticleSet  # §2.2 eqs. (2)-(3)
    ekf: EkfState  # §2.3 3-D filter and its predicted landing
    trail: TrailPoints
    notice: str = ""
    validation: Validation = field(default_factory=Validation.empty)  # ours: the motion gate, confidence and why a frame is not measured
    evidence: RowEvidence | None = None  # ours: what the reported confidence is calibrated from (:mod:`.calibration`)

    @classmethod
    def idle(cls, notice: str) -> GolfIntermediates:
        return cls("idle", Reinit.none(), SearchRegion.empty(), LutSilhouette.empty(), GatedBlobs.empty(),
                   ParticleSet.empty(), EkfState.empty(), TrailPoints.empty(), notice,
                   Validation.empty())
