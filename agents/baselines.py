"""Scripted head policies for the SPL head-control envs, with SB3's ``predict`` signature.

They read only the observation keys ``SPL/ActiveVision-v0`` and ``SPL/LookAround-v0`` share.

- :class:`HeadScan`: sweeps the head yaw sinusoidally at level pitch (the classic SPL scan);
- :class:`LookAtStalest`: points the head at the reachable mapped pole seen least recently,
  scanning while there is none;
- :class:`FixedHead`: looks straight ahead (a lower bound);
- :class:`GreedyInformation`: turns to the view whose poles promise the largest expected
  information about our pose (and whose near robots have gone unseen longest).

Policies are built from the env's :class:`spl_env.config.EnvConfig` (``from_config``) so that
their actions follow the configured head limits and control rate; head angles become actions
through :func:`spl_env.robots.nao.head_action`, clipped to [-1, 1].
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Any

import numpy as np
import numpy.typing as npt

from agents.information_gain import information_gain, range_bearing_jacobian
from perception.geometry import FloatArray, wrap_angle
from spl_env.config import EnvConfig
from spl_env.observations.base import unsquash
from spl_env.observations.poles import RANGE_SCALE_M, SINCE_SEEN_SCALE_S
from spl_env.observations.self_pose import STD_SCALE_M, STD_SCALE_RAD
from spl_env.robots.nao import RobotConfig, head_action, head_target


class ScriptedPolicy(ABC):
    """Base: the head limits, a clock, and SB3's ``predict``."""

    def __init__(self, robot: RobotConfig, control_dt_s: float) -> None:
        self.robot = robot
        self.control_dt_s = control_dt_s
        self.t_s = 0.0

    @classmethod
    def from_config(cls, config: EnvConfig) -> ScriptedPolicy:
        """The policy for an env built from ``config``."""
        return cls(config.robot, config.control_dt_s)

    def reset(self) -> None:
        """Start of an episode."""
        self.t_s = 0.0

    def look(self, yaw_rad: float, pitch_rad: float) -> np.ndarray:
        """The action (2,) float32 whose head target is ``(yaw_rad, pitch_rad)``.

        Targets beyond the joint limits map beyond [-1, 1] and are clipped there: the head then
        looks as far as its joint goes.
        """
        return np.clip(head_action(self.robot, yaw_rad, pitch_rad), -1.0, 1.0).astype(np.float32)

    @abstractmethod
    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Action (2,) float32 for one observation."""

    def predict(
        self,
        obs: dict[str, np.ndarray],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, None]:
        """SB3-style: ``episode_start`` true restarts the policy's clock."""
        if episode_start is not None and np.any(episode_start):
            self.reset()
        action = self.act(obs)
        self.t_s += self.control_dt_s
        return action, None


class HeadScan(ScriptedPolicy):
    """Yaw ``amplitude · sin(2π t / period)`` at level pitch."""

    amplitude_rad = math.radians(90.0)
    period_s = 4.0

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        yaw = self.amplitude_rad * math.sin(2 * math.pi * self.t_s / self.period_s)
        return self.look(yaw, 0.0)


class LookAtStalest(HeadScan):
    """Look at the reachable mapped pole seen least recently; scan while there is none.

    A pole is reachable when turning the head to its joint limit brings it inside the central
    half of the image (``reach_margin_rad`` beyond the yaw limit).
    """

    reach_margin_rad = math.radians(14.0)

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        if "landmarks_mask" not in obs:  # a field without poles: there is never one
            return super().act(obs)
        bearings = np.arctan2(obs["landmarks_sin_bearing"], obs["landmarks_cos_bearing"])
        reachable = (obs["landmarks_mask"] > 0.5) & (
            np.abs(bearings) <= self.robot.head_yaw_limit_rad + self.reach_margin_rad
        )
        if not reachable.any():
            return super().act(obs)
        target = int(np.argmax(np.where(reachable, obs["landmarks_since_seen"], -1.0)))
        return self.look(float(bearings[target]), 0.0)


class FixedHead(ScriptedPolicy):
    """Always look straight ahead at level pitch."""

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return self.look(0.0, 0.0)


class GreedyInformation(HeadScan):
    """Turn the head to the yaw whose view promises the largest pose information gain.

    For each candidate head yaw (a grid over the joint range) the mapped poles that would fall
    inside the image (``view_margin_rad`` from its edges, within ``max_range_m``) are scored by
    the information one range-bearing sighting of each would give about our pose
    (:func:`agents.information_gain.information_gain`; R the sighting's noise plus the pole's own
    map uncertainty). The prior P is the planner's own pose covariance: it adds ``motion_std``
    per step and the information of the poles sighted this step (``landmarks_since_seen`` 0),
    then is rescaled to the believed stds of ``self_pose_std``, so that P keeps the correlations
    that repeated sightings of one pole leave (those stds alone would let one near pole look
    equally informative forever). Robots tracked within ``awareness_radius_m`` that the image
    would hold add ``robot_value`` per second since they were seen (capped at
    ``robot_stale_cap_s``); each yaw's score is averaged with its neighbours' (``centring``
    candidates: a view is worth most where what it holds sits mid-image); turning the head
    costs ``turn_cost`` per radian; a chosen target is held for ``hold_s``. While some pole is
    still unmapped it sweeps the head once (a scan period) every ``explore_period_s``; with
    none mapped (or none on the field) it scans. The constants were set on seeds 0-5 of
    ``SPL/ActiveVision-v1`` in the geometric mode.
    """

    yaw_step_rad = math.radians(5.0)
    view_margin_rad = math.radians(6.0)  # a pole this near the image edge is not counted
    max_range_m = 6.0  # farther poles are not counted
    range_noise = 0.05  # relative range std of a sighting
    bearing_noise_rad = 0.02  # bearing std of a sighting
    min_std = (0.01, 0.01, math.radians(0.5))  # floor of the prior's std (m, m, rad)
    motion_std = (0.005, 0.005, 0.01)  # the planner's pose noise per step (m, m, rad)
    awareness_radius_m = 3.0
    robot_value = 0.1  # score per second since a near robot was seen
    robot_stale_cap_s = 2.0
    turn_cost = 0.02  # score per radian of head turn
    hold_s = 0.3
    explore_period_s = 8.0  # a sweep this often while a pole is unmapped
    centring = 5  # candidates whose scores are averaged (centres what is in view)

    def __init__(self, robot: RobotConfig, control_dt_s: float, half_fov_rad: float) -> None:
        super().__init__(robot, control_dt_s)
        self.half_fov_rad = half_fov_rad
        limit = robot.head_yaw_limit_rad
        half_count = round(limit / self.yaw_step_rad)  # an even grid through 0 and both limits
        self.candidates = np.linspace(-limit, limit, 2 * half_count + 1)
        self.explore_steps = round(self.explore_period_s / control_dt_s)
        self.sweep_steps = round(self.period_s / control_dt_s)
        self.reset()

    @classmethod
    def from_config(cls, config: EnvConfig) -> GreedyInformation:
        hfov_deg = config.sensors.camera.model.hfov_deg
        return cls(config.robot, config.control_dt_s, math.radians(hfov_deg) / 2)

    def reset(self) -> None:
        super().reset()
        self._target_yaw = 0.0
        self._held_s = math.inf
        self._cov: FloatArray | None = None

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        step = round(self.t_s / self.control_dt_s)
        if "landmarks_mask" not in obs or not np.any(obs["landmarks_mask"] > 0.5):
            return super().act(obs)
        jacobians, noise, bearings = self.pole_sightings(obs)
        self._cov = self.track_covariance(obs, jacobians, noise)
        exploring = not np.all(obs["landmarks_mask"] > 0.5)
        if exploring and step % self.explore_steps < self.sweep_steps:
            self._held_s = math.inf  # plan afresh once the sweep ends
            return super().act(obs)
        if self._held_s >= self.hold_s:
            views = self.pole_scores(jacobians[0], noise[0], bearings) + self.robot_scores(obs)
            # the mean over neighbouring yaws peaks mid-plateau: what is in view gets centred
            kernel = np.ones(self.centring)
            scores = np.convolve(views, kernel, mode="same") / np.convolve(
                np.ones_like(views), kernel, mode="same"
            )  # the grid's ends averaged over the neighbours they have
            head_yaw = float(head_target(self.robot, obs["head_angles"])[0])
            scores -= self.turn_cost * np.abs(self.candidates - head_yaw)
            self._target_yaw = float(self.candidates[int(np.argmax(scores))])
            self._held_s = 0.0
        self._held_s += self.control_dt_s
        return self.look(self._target_yaw, 0.0)

    def pole_sightings(
        self, obs: dict[str, np.ndarray]
    ) -> tuple[tuple[FloatArray, FloatArray], tuple[FloatArray, FloatArray], FloatArray]:
        """Jacobians (N, 2, 3) and noise (N, 2, 2) of a sighting of each of the N mapped poles
        within ``max_range_m`` and of the M of them seen this step (M, ...), and the N poles'
        bearings (rad, robot frame)."""
        mapped = obs["landmarks_mask"] > 0.5
        ranges = unsquash(obs["landmarks_range"], RANGE_SCALE_M)
        usable = mapped & (ranges <= self.max_range_m)
        bearings = np.arctan2(obs["landmarks_sin_bearing"], obs["landmarks_cos_bearing"])
        ranges = np.maximum(ranges, 0.1)
        map_std = unsquash(obs["landmarks_std"], STD_SCALE_M)
        heading = math.atan2(obs["self_pose_field"][3], obs["self_pose_field"][2])
        jacobians = range_bearing_jacobian(heading + bearings, ranges)
        noise = np.zeros((len(ranges), 2, 2))
        noise[:, 0, 0] = (self.range_noise * ranges) ** 2 + map_std**2 / 2
        noise[:, 1, 1] = self.bearing_noise_rad**2 + map_std**2 / (2 * ranges**2)
        seen = mapped & (obs["landmarks_since_seen"] <= 0.0)
        return (
            (jacobians[usable], jacobians[seen]),
            (noise[usable], noise[seen]),
            bearings[usable],
        )

    def track_covariance(
        self,
        obs: dict[str, np.ndarray],
        jacobians: tuple[FloatArray, FloatArray],
        noise: tuple[FloatArray, FloatArray],
    ) -> FloatArray:
        """The planner's pose covariance (3, 3) after this step's motion and sightings,
        rescaled to the believed stds."""
        std = np.maximum(
            np.concatenate(
                [
                    unsquash(obs["self_pose_std"][:2], STD_SCALE_M),
                    unsquash(obs["self_pose_std"][2:], STD_SCALE_RAD),
                ]
            ),
            self.min_std,
        )
        cov = np.diag(std**2) if self._cov is None else self._cov + np.diag(self.motion_std) ** 2
        seen_h, seen_r = jacobians[1], noise[1]
        if len(seen_h):
            info = np.linalg.inv(cov) + np.einsum(
                "nji,njk,nkl->il", seen_h, np.linalg.inv(seen_r), seen_h
            )
            cov = np.linalg.inv(info)
        scale = std / np.sqrt(np.diag(cov))
        return cov * np.outer(scale, scale)

    def in_view(self, bearings: FloatArray) -> npt.NDArray[np.bool_]:
        """(C, N) whether each of N bearings (rad) lies inside the image at each candidate yaw."""
        offset = wrap_angle(bearings[None, :] - self.candidates[:, None])
        return np.abs(offset) <= self.half_fov_rad - self.view_margin_rad

    def pole_scores(
        self, jacobians: FloatArray, noise: FloatArray, bearings: FloatArray
    ) -> FloatArray:
        """(C,) information gain of the poles (N, ...) each candidate yaw would see."""
        if self._cov is None:
            raise RuntimeError("pole_scores needs the covariance that act() tracks")
        return np.array(
            [
                information_gain(self._cov, jacobians[v], noise[v]) if v.any() else 0.0
                for v in self.in_view(bearings)
            ]
        )

    def robot_scores(self, obs: dict[str, np.ndarray]) -> FloatArray:
        """(C,) value of the near tracked robots each candidate yaw would see."""
        if "robots_mask" not in obs:
            return np.zeros(len(self.candidates))
        ranges = unsquash(obs["robots_range"], RANGE_SCALE_M)
        near = (obs["robots_mask"] > 0.5) & (ranges < self.awareness_radius_m)
        bearings = np.arctan2(obs["robots_sin_bearing"], obs["robots_cos_bearing"])[near]
        stale_s = np.minimum(
            unsquash(obs["robots_since_seen"][near], SINCE_SEEN_SCALE_S), self.robot_stale_cap_s
        )
        return np.asarray(self.robot_value * (self.in_view(bearings) @ stale_s), dtype=np.float64)


BASELINES: dict[str, type[ScriptedPolicy]] = {
    "scan": HeadScan,
    "look_at_stalest": LookAtStalest,
    "fixed": FixedHead,
    "greedy_information": GreedyInformation,
}
