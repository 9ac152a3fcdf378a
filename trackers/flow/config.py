"""Configuration of the gradient-flow tracker (seed 004), with the paper's parameters as defaults."""

from __future__ import annotations

from dataclasses import dataclass

from trackreplay.trackers.lifecycle import LifecycleConfig


@dataclass(frozen=True)
class FlowConfig:
    """Parameters; the paper's where it gives them (§5: FOV 51×51, 5×5 Beaudet operators, ε = 0.5).

    The rest were chosen on the flow-sim scenes (texture, "camera" and "coins" backgrounds).
    """

    fov: int = 51
    neighbourhood: int = 5  # n×n least-squares neighbourhood, 3, 5 or 7 (eq. 5)
    derivative: int = 5  # support of the Beaudet operators, 3, 5 or 7
    derivative_order: int = 3  # degree of the fitted surface: 3 gives Beaudet's 5×5 operators
    # cond₂(G) bound (eq. 8): errors in the derivatives are amplified at most ~20× in the flow. No bound
    # lost the disc on the "camera" background, 50 drifted 13 px on "coins", 10 starved the disc of flow
    cond_max: float = 20.0
    # mean squared gradient over the neighbourhood (grey levels²/px²) below which a region is flat
    min_energy: float = 1.0
    epsilon: float = 0.5  # px/frame (eq. 11; 3× the background flow's std in the paper)
    alpha: float = 0.5  # acceleration memory of the Gauss–Markov model (eq. 23), 0 < α < 1
    # acceleration driving noise, (px/frame²)²: integer-pixel motion makes the velocity jump by 1
    # px/frame between frames, so the filter must follow such steps
    q: float = 1.0
    r_pos: float = 0.25  # centroid observation variance, px² (measured centroid error ≈ 0.4 px rms)
    r_vel: float = 0.5  # eq. 11 velocity variance, (px/frame)²: it reads ~3/4 of the speed (see velocity.py)
    p0: tuple[float, float, float] = (1.0, 16.0, 1.0)  # initial variances of x, ẋ, ẍ (speed unknown, ≤ 4)
    online: bool = True  # §4.1: one refinement per frame, warm-started from the previous flow
    refine_iterations: int = 4  # offline: solves of eq. 7/9 at most (eq. 10 may stop earlier)
    sigmas: tuple[float, ...] = (2.0, 1.0, 0.5, 0.0)  # coarse-to-fine blur, per iteration or per frame
    pyramid_levels: int = 0  # offline only, not in the paper: Gaussian-pyramid levels above the image
    hist_range: float = 8.0  # histograms of u and v span ±hist_range px/frame
    hist_bin: float = 0.25
    init_center: tuple[float, float] | None = None  # start when the first frame has no "target" hint
    lost_after: int = 10  # frames without moving pixels before the track is "lost"

    def __post_init__(self) -> None:
        if self.fov < 9 or self.fov % 2 == 0:
            raise ValueError(f"fov must be odd and at least 9, not {self.fov}")
        if self.neighbourhood not in (3, 5, 7):
            raise ValueError(f"neighbourhood must be 3, 5 or 7, not {self.neighbourhood}")
        if self.derivative not in (3, 5, 7):
            raise ValueError(f"derivative must be 3, 5 or 7, not {self.derivative}")
        if self.derivative_order not in (1, 2, 3) or (self.derivative == 3 and self.derivative_order == 3):
            raise ValueError(f"derivative_order must be 1, 2 or 3 (at most 2 for a 3x3 window), not {self.derivative_order}")
        if not 0.0 < self.alpha < 1.0:
            raise ValueError(f"alpha must lie in (0, 1) (eq. 23), not {self.alpha}")
        if min(self.q, self.r_pos, self.r_vel) <= 0 or len(self.p0) != 3 or min(self.p0) <= 0:
            raise ValueError("q, r_pos, r_vel and the three p0 variances must be positive")
        if self.cond_max < 1.0 or self.min_energy < 0 or self.epsilon < 0:
            raise ValueError("cond_max must be >= 1 and min_energy, epsilon >= 0")
        if not self.sigmas or min(self.sigmas) < 0 or self.refine_iterations < 1 or self.pyramid_levels < 0:
            raise ValueError("sigmas must be non-empty and >= 0, refine_iterations >= 1, pyramid_levels >= 0")
        if self.hist_bin <= 0 or self.hist_range <= 0 or self.lost_after < 1:
            raise ValueError("hist_bin, hist_range and lost_after must be positive")
        if self.init_center is not None and len(self.init_center) != 2:
            raise ValueError(f"init_center must be (x, y), not {self.init_center}")

    @property
    def lifecycle(self) -> LifecycleConfig:
        """The track's life (trackers.lifecycle): "lost" on the lost_after-th frame in a row without moving pixels."""
        return LifecycleConfig(lost_after=self.lost_after)

    def sigma_at(self, iteration: int) -> float:
        """Blur of the given refinement (offline) or frame (on-line); the last value repeats."""
        return float(self.sigmas[min(iteration, len(self.sigmas) - 1)])
