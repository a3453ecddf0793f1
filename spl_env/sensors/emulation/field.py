"""The fast geometric camera mode's field features: the map's features in view of the camera
at the robot's true pose (:func:`perception.field.visibility.visible_features`), with the
noise of the pipeline's ``feature_view`` configuration (not yet fitted to the rendered
detector). The camera pose is the one the joints report (no sway), as the detector assumes."""

from __future__ import annotations

import numpy as np

from perception.field.features import FieldFeature
from perception.field.field_map import FieldMap
from perception.field.visibility import FeatureViewConfig, visible_features
from perception.types import CameraModel, CameraState
from spl_env.robots.nao import NaoRobot, camera_state_for
from spl_env.sim.world import BulletWorld


class GeometricFieldFeatures:
    """Emulates the ``vision`` field-feature provider without rendering (with ``bottom``, the
    ``vision_both_cameras`` one: the bottom camera's features after the top one's)."""

    def __init__(
        self,
        field_map: FieldMap,
        camera: CameraModel,
        config: FeatureViewConfig,
        bottom: bool = False,
    ) -> None:
        self.field_map = field_map
        self.camera = camera
        self.config = config
        self.bottom = bottom

    def observe(
        self,
        world: BulletWorld,
        robot: NaoRobot,
        camera_state: CameraState,
        rng: np.random.Generator,
        blur_px: float,
    ) -> tuple[FieldFeature, ...]:
        """This frame's field features (robot frame) from ``robot``'s true pose."""
        features = visible_features(
            self.field_map, robot.pose, self.camera, camera_state, self.config, rng
        )
        if not self.bottom:
            return features
        bottom = camera_state_for(robot.config, robot.head, "bottom")
        return features + visible_features(
            self.field_map, robot.pose, self.camera, bottom, self.config, rng
        )
