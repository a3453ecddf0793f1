"""A frame's natural landmarks: 1D SURF features on the horizon band, with their bearings.

:func:`horizon_features` takes an RGB image, sums its grey horizon band
(:func:`perception.landmarks.horizon.horizon_band`), extracts the band's 1D SURF features
(:func:`perception.landmarks.surf1d.extract_features`) and keeps those whose column shows the
horizon. Each feature's bearing is the direction of its pixel's ray on the horizon, measured in
the horizontal plane from the camera's heading (rad, positive to the left): the camera's heading
on the body is the head yaw, so the body's heading change between two frames is the mode of
the bearing changes less the head's yaw change (:mod:`perception.landmarks.visual_odometry`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, camera_rotation, pixel_rays
from perception.landmarks.horizon import HorizonConfig, horizon_band
from perception.landmarks.surf1d import Surf1dConfig, Surf1dFeatures, extract_features
from perception.types import CameraModel, CameraState
from perception.validation import check_nested_configs


@dataclass(frozen=True, kw_only=True)
class HorizonFeatureConfig:
    """The horizon band and the 1D SURF settings of :func:`horizon_features`."""

    horizon: HorizonConfig = field(default_factory=HorizonConfig)
    surf: Surf1dConfig = field(default_factory=Surf1dConfig)

    def __post_init__(self) -> None:
        check_nested_configs(self)


@dataclass(frozen=True, eq=False)
class HorizonFeatures:
    """One frame's horizon features: ``features`` (N of them), their ``bearings`` (N,) (rad,
    from the camera's heading, left positive) and the frame's ``head_yaw`` (rad)."""

    features: Surf1dFeatures
    bearings: FloatArray
    head_yaw: float

    def __len__(self) -> int:
        return len(self.features)

    def without(self, drop: NDArray[np.bool_]) -> HorizonFeatures:
        """These features less those where ``drop`` (N,) is True."""
        keep = ~np.asarray(drop, dtype=bool)
        return HorizonFeatures(
            features=_subset(self.features, keep),
            bearings=self.bearings[keep],
            head_yaw=self.head_yaw,
        )


def horizon_features(
    image: NDArray[np.uint8],
    camera: CameraModel,
    state: CameraState,
    config: HorizonFeatureConfig,
) -> HorizonFeatures:
    """The horizon features of an RGB ``image`` (H, W, 3) seen by ``camera`` at ``state``."""
    gray = cv2.cvtColor(np.ascontiguousarray(image), cv2.COLOR_RGB2GRAY)
    band = horizon_band(gray, camera, state, config.horizon)
    found = extract_features(band.signal, config.surf, band.columns)
    features = _subset(found, band.valid[found.index])
    rows = band.rows[features.index]
    rays = pixel_rays(
        np.column_stack([features.x, rows]), camera.fx, camera.fy, camera.cx, camera.cy
    )
    rotation = camera_rotation(0.0, state.head_pitch + state.tilt)  # the camera's heading frame
    level = rays @ rotation.T
    bearings = np.arctan2(level[:, 1], level[:, 0])
    bearings.flags.writeable = False
    return HorizonFeatures(features=features, bearings=bearings, head_yaw=float(state.head_yaw))


def _subset(features: Surf1dFeatures, keep: NDArray[np.bool_]) -> Surf1dFeatures:
    """The features where ``keep`` (N,) is True, arrays read-only like the original's."""
    subset = Surf1dFeatures(**{name: array[keep] for name, array in vars(features).items()})
    for array in vars(subset).values():
        array.flags.writeable = False
    return subset
