"""Our robot's own readings: head joint angles, sonar echoes, the episode clock."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray
from spl_env.observations.base import EncoderInput, box, squash
from spl_env.robots.nao import RobotConfig, head_action

SONAR_SCALE_M = 1.0  # squashing scale of sonar echo distance (m)


@dataclass(frozen=True)
class HeadEncoder:
    """``head_angles`` (2,): the joints' yaw and pitch as the head action that targets them
    (:func:`spl_env.robots.nao.head_action`): yaw / 119.5°, pitch [-38.5°, 29.5°] -> [-1, 1]."""

    robot: RobotConfig
    requires: tuple[str, ...] = ()

    def spaces(self) -> dict[str, spaces.Box]:
        return {"head_angles": box(-1.0, 1.0, 2)}

    def encode(self, data: EncoderInput) -> dict[str, FloatArray]:
        joints = data.frame.camera_state  # head angles as the joint sensors report them
        if joints is None:
            raise ValueError("HeadEncoder needs frame.camera_state, which is None")
        return {"head_angles": head_action(self.robot, joints.head_yaw, joints.head_pitch)}


@dataclass(frozen=True)
class SonarEncoder:
    """``sonar`` (3,): nearest echo of the left, middle and right sectors, d / (d + 1 m);
    1 when no echo (or no sonar)."""

    requires: tuple[str, ...] = ()
    frame_reads: ClassVar[tuple[str, ...]] = ("sonar",)

    def spaces(self) -> dict[str, spaces.Box]:
        return {"sonar": box(0.0, 1.0, 3)}

    def encode(self, data: EncoderInput) -> dict[str, FloatArray]:
        nearest = np.ones(3)  # no echo in a sector reads as "far"
        sonar = data.frame.sonar
        if sonar is not None:
            closest = np.where(np.isnan(sonar), np.inf, sonar).min(axis=1)
            echo = np.isfinite(closest)
            nearest[echo] = squash(closest[echo], SONAR_SCALE_M)
        return {"sonar": nearest}


@dataclass(frozen=True)
class EpisodeClockEncoder:
    """``time_fraction`` (1,): elapsed time / ``episode_s``."""

    episode_s: float
    requires: tuple[str, ...] = ()

    def spaces(self) -> dict[str, spaces.Box]:
        return {"time_fraction": box(0.0, 1.0, 1)}

    def encode(self, data: EncoderInput) -> dict[str, FloatArray]:
        return {"time_fraction": np.array([min(data.output.time_s / self.episode_s, 1.0)])}
