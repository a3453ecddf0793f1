"""The ball as perception believes it, relative to our robot."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray
from perception.representations import BALL
from perception.tracking.ball_filter import position_std
from perception.types import BallEstimate
from spl_env.observations.base import EncoderInput, box, squash
from spl_env.observations.poles import RANGE_SCALE_M, SINCE_SEEN_SCALE_S
from spl_env.observations.robots import SPEED_SCALE_MPS
from spl_env.observations.self_pose import STD_SCALE_M

UNSEEN_SINCE = 1.0  # ``ball_since_seen`` while no ball is believed (unseen yet, or lost)


@dataclass(frozen=True)
class BallEncoder:
    """The believed ball relative to our robot (robot frame; perception's egocentric estimate):

    ``ball_bearing`` (2,) cos and sin of its bearing, ``ball_range`` (1,) r / (r + 3 m),
    ``ball_velocity`` (2,) each robot-frame component v / (|v| + 0.3 m/s), ``ball_std`` (1,)
    s / (s + 0.5 m) with s = sqrt(trace of its position covariance), ``ball_since_seen`` (1,)
    t / (t + 2 s). While no ball is believed (before its first sighting, or once the filter
    lost it): bearing (1, 0), range, velocity 0, std and since-seen 1.
    """

    requires: tuple[str, ...] = (BALL,)

    def spaces(self) -> dict[str, spaces.Box]:
        return {
            "ball_bearing": box(-1.0, 1.0, 2),
            "ball_range": box(0.0, 1.0, 1),
            "ball_velocity": box(-1.0, 1.0, 2),
            "ball_std": box(0.0, 1.0, 1),
            "ball_since_seen": box(0.0, 1.0, 1),
        }

    def encode(self, data: EncoderInput) -> dict[str, FloatArray]:
        ball = data.output.get_as(BALL, BallEstimate)
        if not ball.known:
            return {
                "ball_bearing": np.array([1.0, 0.0]),
                "ball_range": np.zeros(1),
                "ball_velocity": np.zeros(2),
                "ball_std": np.ones(1),
                "ball_since_seen": np.full(1, UNSEEN_SINCE),
            }
        x, y, vx, vy = ball.relative
        range_m, bearing = math.hypot(x, y), math.atan2(y, x)
        velocity = np.array([vx, vy])
        std = position_std(ball.relative_cov)
        since = max(data.output.time_s - ball.last_seen_s, 0.0)
        return {
            "ball_bearing": np.array([np.cos(bearing), np.sin(bearing)]),
            "ball_range": np.array([squash(range_m, RANGE_SCALE_M)]),
            "ball_velocity": velocity / (np.abs(velocity) + SPEED_SCALE_MPS),
            "ball_std": np.array([squash(std, STD_SCALE_M)]),
            "ball_since_seen": np.array([squash(since, SINCE_SEEN_SCALE_S)]),
        }
