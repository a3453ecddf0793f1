"""``SPL/ActiveVision-v0``: decide where the robot looks while its body walks a scripted path."""

from __future__ import annotations

import math
import time
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from perception.pipeline import PerceptionPipeline
from perception.types import PerceptionOutput, SensorFrame
from spl_env.behaviours import WaypointWalker
from spl_env.config import EnvConfig, with_overrides
from spl_env.envs.observation import ObservationBuilder
from spl_env.rendering import TopDownView, draw_detections, side_by_side
from spl_env.simulation import SplSimulation, WorldState
from spl_env.timing import StepTimes


class ActiveVisionEnv(gym.Env[dict[str, Any], np.ndarray]):
    """Active vision on an SPL field: move the head so that EKF SLAM stays accurate and certain.

    Our Nao walks a scripted path (``body_behaviour="patrol"``: random waypoints inside the
    field; ``"square"``: seed 000's square walk) among four other robots that walk about and
    occlude the view. Six two-coloured poles stand outside the touch lines. Every control step
    (10 Hz) renders one camera frame; a front end detects poles in it and an EKF SLAM back end
    fuses them with noisy walk odometry. The observation is what perception believes, never
    ground truth.

    **Perception** (seed 000), chosen by keyword: ``frontend="colour"`` (HSV colour filter) or
    ``"cnn"`` (the packaged CenterNet-style detector; rendered camera mode only);
    ``backend="classic"`` (Algorithm 5), ``"gated"`` (sightings off by more than 0.4 m or
    π/3 from the prediction are dropped), ``"minimal_view"`` (a pole enters the map after
    ``min_views`` sightings in one place, default 3) or ``"fej"`` (first-estimates Jacobians);
    ``min_views=n`` and ``gate="thresholds" | "mahalanobis" | "none"`` combine with any back
    end. The defaults are the CNN (SLAM takes its detections scoring 0.6 or more with both
    band colours seen) with the gated back end (README, "Choosing the defaults").

    **Action**: ``Box(-1, 1, (2,), float32)``, the head target: yaw ``a[0] * 119.5°`` and pitch
    from ``-38.5°`` (``a[1] = -1``, up) to ``+29.5°`` (``a[1] = 1``, down), linear in between.
    The head turns towards the target at up to 4 rad/s. NaN or out-of-range actions raise
    ``ValueError``.

    **Observation** (``Dict`` of float32 ``Box``; L = 6 landmark ids, index = id):

    ========================  ======  =======================================================
    key                       shape   content
    ========================  ======  =======================================================
    ``self_pose_field``       (4,)    SLAM pose: x / 5.2 m, y / 3.7 m (carpet half sizes,
                                      saturating at ±1.5), cos θ, sin θ
    ``self_pose_std``         (3,)    std of x, y (m) and θ (rad), each as s / (s + 0.5)
    ``head_angles``           (2,)    head yaw / 119.5°; pitch, [-38.5°, 29.5°] -> [-1, 1]
    ``landmarks_cos_bearing`` (L,)    cos of each mapped pole's bearing from the SLAM pose
                                      (robot frame); 0 if not mapped
    ``landmarks_sin_bearing`` (L,)    sin of that bearing; 0 if not mapped
    ``landmarks_range``       (L,)    r / (r + 3 m), r its range from the SLAM pose; 0 if not
                                      mapped
    ``landmarks_mask``        (L,)    1 where the pole is in the SLAM map
    ``landmarks_std``         (L,)    s / (s + 0.5 m), s = sqrt(trace cov) of a mapped pole;
                                      1 if not mapped
    ``landmarks_since_seen``  (L,)    time since last detection t / (t + 2 s); 1 if never
    ``sonar``                 (3,)    nearest echo of the left, middle and right sonar
                                      sectors, d / (d + 1 m); 1 when no echo
    ``time_fraction``         (1,)    elapsed time / episode length
    ========================  ======  =======================================================

    **Reward** per step, each term in ``info["reward_terms"]``:

    - ``position_error``: ``-error_weight * |p_true - p_slam|`` (m), the true localisation error;
    - ``uncertainty``: ``-uncertainty_weight * sqrt(trace Σ_xy)`` (m), the believed position std.

    **Episode**: truncated after ``episode_s`` (60 s, 600 steps); never terminated. The body's
    scripted walk steers on the true pose (it is scenery, not the policy's concern).

    **info** (after ``reset`` and every ``step``; SI units, field frame): ``perception`` (pose,
    pose_cov, odometry_pose, landmarks, landmark_ids, landmark_covs, detections),
    ``ground_truth`` (robot_pose, head, landmarks, landmark_ids, robots, robot_teams, ball),
    ``reward_terms``, ``timing`` (physics, render, sensors, perception seconds; a read-only
    mapping that compares equal across runs because seconds measure the host, not the world).
    Robot tracks and the circle map of ARCHITECTURE §5 are not in v0: this env's perception
    has no robot tracker or laser mapping yet.

    **Camera modes** (``camera_mode``): ``"rendered"`` (default) renders a frame and runs the
    front end on it; ``"geometric"`` (about 10x faster) projects the poles' band centres
    instead, keeps each with the rendered pipeline's fitted chance under the frame's motion blur
    and adds fitted pixel noise, then measures with the same model. The geometric mode makes no
    false detections and ignores lighting randomisation and image noise (it was fitted under
    default lighting). It emulates the colour front end: pass ``frontend="colour"`` with it
    (the default ``"cnn"`` is refused).

    Keyword arguments override :class:`spl_env.config.EnvConfig` fields by name.

    Version history: v0, first release.
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012

    def __init__(
        self, config: EnvConfig | None = None, render_mode: str | None = None, **overrides: Any
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']} or None, "
                f"got {render_mode!r}"
            )
        self.config = with_overrides(config or EnvConfig(), **overrides)
        self.render_mode = render_mode
        self.sim = SplSimulation(self.config.sim)
        scene = self.config.sim.scene
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.config.sim.control_dt_s)}
        self.codes = self.sim.pole_codes
        self.observation_builder = ObservationBuilder(
            dimensions=scene.dimensions,
            robot=self.config.sim.robot,
            n_landmarks=len(self.codes),
            episode_s=self.config.episode_s,
        )
        self.observation_space = self.observation_builder.space()
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self._top_down = TopDownView(scene.dimensions)
        self._pipeline: PerceptionPipeline | None = None
        self._walker: WaypointWalker | None = None
        self._state: WorldState | None = None
        self._frame: SensorFrame | None = None
        self._output: PerceptionOutput | None = None
        self._steps = 0
        self._closed = False

    # ----- gymnasium API ------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        super().reset(seed=seed)
        rng = self.np_random
        start, waypoints = self._body_plan(rng)
        self._walker = WaypointWalker(
            self.config.walker, self.config.sim.scene.dimensions, rng, waypoints=waypoints
        )
        # the filter's start belief: the true start off by a draw from its own prior
        believed_start = start + rng.normal(0.0, self.config.perception.slam.initial_pose_std)
        scene = self.config.sim.scene
        self._pipeline = PerceptionPipeline(
            self.config.perception,
            self.config.sim.camera.model,
            self.codes,
            scene.poles.geometry,
            believed_start,
        )
        self._state, self._frame, sim_timing = self.sim.reset(rng, start)
        t0 = time.perf_counter()
        self._output = self._pipeline.step(self._frame)
        timing = StepTimes(**sim_timing, perception=time.perf_counter() - t0)
        self._steps = 0
        return self._observation(), self._info(self._reward_terms(), timing)

    def step(
        self, action: np.ndarray
    ) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        if self._pipeline is None or self._walker is None or self._state is None:
            raise RuntimeError("call reset() before step()")
        head_target = self._head_target(action)
        walk = self._walker.command(
            self._state.robot_pose, self.config.sim.control_dt_s, blocked=self._state.blocked
        )
        self._state, self._frame, sim_timing = self.sim.step(walk, head_target)
        t0 = time.perf_counter()
        self._output = self._pipeline.step(self._frame)
        timing = StepTimes(**sim_timing, perception=time.perf_counter() - t0)
        self._steps += 1
        terms = self._reward_terms()
        truncated = self._steps >= self.config.max_steps
        return (
            self._observation(),
            float(sum(terms.values())),
            False,
            truncated,
            self._info(terms, timing),
        )

    def render(self) -> NDArray[np.uint8] | None:
        """``rgb_array``: (H, W, 3) uint8, the top-down field beside the camera image."""
        if self.render_mode is None:
            gym.logger.warn("render() called with render_mode=None; pass render_mode='rgb_array'")
            return None
        state, frame, output = self._current()
        top = self._top_down.draw(state, output, self.codes)
        image = frame.image if frame.image is not None else self.sim.camera_view()
        cam = draw_detections(image, output.observations)
        return side_by_side(top, cam)

    def close(self) -> None:
        if not self._closed:
            self.sim.close()
            self._closed = True

    @property
    def perception(self) -> PerceptionPipeline:
        """The perception stack of the current episode."""
        if self._pipeline is None:
            raise RuntimeError("call reset() before reading perception")
        return self._pipeline

    @property
    def sensor_frame(self) -> SensorFrame:
        """What the robot's sensors delivered in the last step (for testing perception)."""
        if self._frame is None:
            raise RuntimeError("call reset() before reading sensor_frame")
        return self._frame

    # ----- pieces -------------------------------------------------------------------------
    def _head_target(self, action: np.ndarray) -> np.ndarray:
        a = np.asarray(action, dtype=np.float64)
        if a.shape != (2,):
            raise ValueError(f"action must have shape (2,), got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"action must be finite, got {a.tolist()}")
        if np.any(np.abs(a) > 1.0 + 1e-6):
            raise ValueError(f"action must lie in [-1, 1], got {a.tolist()}")
        cfg = self.config.sim.robot
        yaw = a[0] * cfg.head_yaw_limit_rad
        pitch = cfg.head_pitch_min_rad + (a[1] + 1.0) / 2.0 * (
            cfg.head_pitch_max_rad - cfg.head_pitch_min_rad
        )
        return np.array([yaw, pitch])

    def _body_plan(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray | None]:
        """Start pose (3,) and waypoints ((N, 2) or None for random ones) of our robot's walk."""
        dims = self.config.sim.scene.dimensions
        if self.config.body_behaviour == "square":
            h = self.config.square_side_m / 2
            centre = np.array([rng.uniform(-1.0, 1.0), rng.uniform(-0.5, 0.5)])
            corners = centre + np.array([[h, -h], [h, h], [-h, h], [-h, -h]])
            return np.array([*corners[3], 0.0]), corners
        start = np.array(
            [
                rng.uniform(-dims.half_length_m + 1.0, dims.half_length_m - 1.0),
                rng.uniform(-dims.half_width_m + 1.0, dims.half_width_m - 1.0),
                rng.uniform(-math.pi, math.pi),
            ]
        )
        return start, None

    def _current(self) -> tuple[WorldState, SensorFrame, PerceptionOutput]:
        """This step's truth, sensor frame and perception output."""
        if self._state is None or self._frame is None or self._output is None:
            raise RuntimeError("call reset() first")
        return self._state, self._frame, self._output

    def _observation(self) -> dict[str, np.ndarray]:
        _, frame, output = self._current()
        joints = frame.camera_state  # head angles as the joint sensors report them
        head = np.array([joints.head_yaw, joints.head_pitch])
        return self.observation_builder.build(output, head, frame.sonar)

    def _reward_terms(self) -> dict[str, float]:
        state, _, output = self._current()
        slam = output.slam
        error = float(np.hypot(*(state.robot_pose[:2] - slam.pose[:2])))
        std = float(math.sqrt(max(np.trace(slam.pose_cov[:2, :2]), 0.0)))
        return {
            "position_error": -self.config.error_weight * error,
            "uncertainty": -self.config.uncertainty_weight * std,
        }

    def _info(self, terms: dict[str, float], timing: StepTimes) -> dict[str, Any]:
        s, _, output = self._current()
        slam = output.slam
        return {
            "perception": {
                "pose": slam.pose.copy(),
                "pose_cov": slam.pose_cov.copy(),
                "odometry_pose": output.odometry_pose.copy(),
                "landmarks": slam.landmarks.copy(),
                "landmark_ids": slam.landmark_ids.copy(),
                "landmark_covs": slam.landmark_covs.copy(),
                "detections": [
                    (o.landmark_id, o.range_m, o.bearing_rad) for o in output.observations
                ],
            },
            "ground_truth": {
                "robot_pose": s.robot_pose.copy(),
                "head": s.head.copy(),
                "landmarks": s.landmarks.copy(),
                "landmark_ids": s.landmark_ids.copy(),
                "robots": s.robots.copy(),
                "robot_teams": s.robot_teams.copy(),
                "ball": s.ball.copy(),
            },
            "reward_terms": terms,
            "timing": timing,
        }
