"""What one observation of the kitchen hands to the rest of teachbot: plain data."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class SceneTruth:
    """Hidden ground truth: only the scripted teacher and the evaluation may read it."""

    concepts: tuple[str, ...]
    kinds: tuple[str, ...]
    body_ids: tuple[int, ...]
    positions: np.ndarray  # (n, 3) true centres from the simulator
    sizes: np.ndarray      # (n, 3) true length, width, height
    states: tuple[str, ...] = ()     # state of each object ("boxed", "in-pot"; "as-is" when a kind has none)
    masses: tuple[float, ...] = ()   # true mass, kg
    yaws: tuple[float, ...] = ()     # true yaw on the counter, radians


@dataclass(frozen=True)
class Scene:
    """One observation: object ``i`` is shown to people as number ``i + 1``."""

    scene_id: int
    X: np.ndarray                     # (n objects, |F|) float64
    feature_names: tuple[str, ...]
    positions: np.ndarray             # (n, 3) perceived bounding-box centres (for pointing)
    tops: np.ndarray                  # (n,) perceived top height of each object
    colours: np.ndarray               # (n, 3) perceived mean colour in 0..1
    truth: SceneTruth = field(repr=False)
    outlines: np.ndarray | None = field(default=None, repr=False)  # (n, 4, 2) perceived footprint box corners
    stage: int = 0                    # how many state changes the world has been through (prepare-lunch)

    @property
    def n_objects(self) -> int:
        return self.X.shape[0]

    def feature(self, name: str) -> np.ndarray:
        """One named feature column."""
        return self.X[:, self.feature_names.index(name)]
