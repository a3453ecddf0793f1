"""Labelled camera frames for training and testing object detectors (seed 000 §3.4.1).

``python -m spl_env.datasets --out data/poles --images 6000 --seed 0 --scenes 60`` renders
frames of the full scene (poles, goals, ball, poster boards, our robot and four others) with
domain randomisation and writes, under ``--out``:

- ``images/000000.png``, ... : (240, 320, 3) RGB frames;
- ``labels.jsonl``: one JSON object per image (see :meth:`FrameSampler.sample`);
- ``meta.json``: class names, the configuration, the seed and the camera model.

Labels come from the renderer's body-id label buffer: an object's box spans the min..max
column and row of its labelled pixels (pixel i is centred at u = i). Poles also carry the
projection of the junction of their two colour bands on the pole axis (``keypoint``, px), the
true range and bearing from the robot (robot frame) and an occluded fraction. The images are
spread over ``--scenes`` scenes (poster draws); within a scene each frame draws, from one
seeded generator per scene:

- lighting (direction, colour, ambient, exposure, a bright window side; default lighting in
  ``default_lighting_probability`` of the frames), sensor noise level and a camera turn rate
  for motion blur;
- the robot's pose: with ``aim_probability`` aimed so that a random pole is 0.5-6.5 m away and
  near the image centre (with ``occluder_probability`` another robot steps between camera and
  pole), otherwise anywhere on the field looking anywhere (negatives and clutter); head angles
  as in ``benchmarks/colour_filter_accuracy.py`` and mid-gait sway in ``sway_probability``;
- the other robots anywhere on the field, the ball either in front of the camera or anywhere.
"""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, project_points, range_bearing
from perception.types import PoleCode
from perception.validation import check_nested_configs, check_positive, check_reals
from perception.vision.cnn_detector import OBJECT_CLASSES, pole_class_name
from spl_env.robots.nao import NaoRobot, RobotConfig
from spl_env.scenes.spl_field import SceneConfig, SplFieldScene
from spl_env.sensors.camera import Camera, CameraConfig, EpisodeLighting, LightingRandomisation
from spl_env.sim.world import BulletWorld

N_OTHER_ROBOTS = 4
_HEAD_YAW_RAD = 1.2  # head yaw drawn in ±this (as the colour-filter benchmark)
_HEAD_PITCH_RAD = (-0.25, 0.45)  # head pitch range (rad, positive looks down)
_AIM_SPREAD_RAD = 0.45  # aimed pole's azimuth off the optical axis, ±this (HFOV/2 = 0.49)
_ROBOT_AREA_MARGIN_M = (0.2, 0.1)  # where our robot may stand: field half sizes plus these (x, y)


@dataclass(frozen=True, kw_only=True)
class DatasetConfig:
    """How frames are drawn; probabilities per frame, distances in metres, rates in rad/s."""

    aim_probability: float = 0.6  # frames aimed at a random pole
    aim_range_m: tuple[float, float] = (0.5, 6.5)  # distance to the aimed pole
    occluder_probability: float = 0.3  # of aimed frames: a robot between camera and pole
    sway_probability: float = 0.5  # frames taken mid-gait (sway the camera state misses)
    blur_probability: float = 0.5  # frames with a turning camera (motion blur)
    max_yaw_rate_rps: float = 3.0  # camera turn rate drawn in ±this for blurred frames
    noise_std: tuple[float, float] = (0.0, 4.0)  # sensor noise std range (8-bit levels)
    default_lighting_probability: float = 0.1  # frames under even default lighting
    ball_in_front_probability: float = 0.5  # frames with the ball placed in front of the camera
    lighting: LightingRandomisation = field(default_factory=LightingRandomisation)

    def __post_init__(self) -> None:
        check_nested_configs(self)
        for name in (
            "aim_probability",
            "occluder_probability",
            "sway_probability",
            "blur_probability",
            "default_lighting_probability",
            "ball_in_front_probability",
        ):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and 0.0 <= value <= 1.0):
                raise ValueError(f"DatasetConfig.{name} must be in [0, 1], got {value!r}")
        for name, low in (("aim_range_m", 0.3), ("noise_std", 0.0)):
            check_reals("DatasetConfig", name, getattr(self, name), 2)
            lo, hi = getattr(self, name)
            if not low <= lo <= hi:
                raise ValueError(
                    f"DatasetConfig.{name} must be (lo, hi) with {low} <= lo <= hi, "
                    f"got {getattr(self, name)}"
                )
        check_positive("DatasetConfig", "max_yaw_rate_rps", self.max_yaw_rate_rps, allow_zero=True)


def class_names(codes: tuple[PoleCode, ...]) -> tuple[str, ...]:
    """Detector classes: one per pole in ``codes`` order, then goal post, ball and robot."""
    return (*(pole_class_name(c) for c in codes), *OBJECT_CLASSES)


class FrameSampler:
    """One scene (poster draw) with our robot and the others; draws labelled frames.

    The world is built from the envs' modules (:class:`spl_env.scenes.spl_field.SplFieldScene`,
    :class:`spl_env.robots.nao.NaoRobot`, :class:`spl_env.sensors.camera.Camera`). ``rng``
    draws the posters (``scene.scene_seed`` is not used) and, afterwards, every frame. Call
    :meth:`close` when done.
    """

    def __init__(
        self,
        config: DatasetConfig,
        rng: np.random.Generator,
        scene: SceneConfig | None = None,
        camera: CameraConfig | None = None,
    ) -> None:
        self.config = config
        self.rng = rng
        self.camera_config = camera or CameraConfig()
        self.world = BulletWorld(time_step_s=0.01)
        self.field = SplFieldScene(self.world, scene or SceneConfig(), poster_rng=rng)
        self.scene = self.field.config
        robot_config = RobotConfig()
        self.robot = NaoRobot(self.world, "self", team=0, config=robot_config)
        self.others = [
            NaoRobot(self.world, f"robot_{i}", team=i % 2, config=robot_config)
            for i in range(N_OTHER_ROBOTS)
        ]
        self.codes = self.field.codes
        self.poles = self.field.landmarks  # (L, 2), row k is pole self.codes[k]
        self.classes = class_names(self.codes)
        self._class_id = {name: i for i, name in enumerate(self.classes)}

    def close(self) -> None:
        """Release the physics client."""
        self.world.close()

    def sample(self) -> tuple[NDArray[np.uint8], dict[str, Any]]:
        """Draw and render one frame: image (240, 320, 3) uint8 RGB and its label record.

        The record holds ``camera_state`` (what the joints report, robot frame:
        ``position`` (3,) m, ``head_yaw``, ``head_pitch``, ``tilt`` rad), ``camera_world``
        (the true camera ``position`` (3,) and ``rotation`` (3, 3) in the field frame, sway
        included), ``robot_pose`` (3,) field frame, ``render`` (the randomised settings) and
        ``objects`` (see :meth:`_objects`); the caller adds ``image``.
        """
        cfg, rng = self.config, self.rng
        aimed = self._place_robots()
        if rng.uniform() < cfg.sway_probability:
            self.robot.velocity = np.asarray(self.robot.config.max_speed) * rng.uniform(
                -1.0, 1.0, size=3
            )
            self.robot.gait_phase = rng.uniform(0.0, 2 * math.pi)
            self.robot.sync()
        swaying = bool(np.any(self.robot.velocity != 0.0))
        position, rotation = self.robot.camera_pose_world()
        self._place_ball(position, rotation)
        default = rng.uniform() < cfg.default_lighting_probability
        lighting = (
            EpisodeLighting.default() if default else EpisodeLighting.sample(cfg.lighting, rng)
        )
        noise = float(rng.uniform(*cfg.noise_std))
        blurred = rng.uniform() < cfg.blur_probability
        yaw_rate = float(rng.uniform(-1.0, 1.0) * cfg.max_yaw_rate_rps) if blurred else 0.0
        camera = Camera(CameraConfig(model=self.camera_config.model, noise_std=noise))
        image, labels = camera.render(
            self.world, position, rotation, lighting, rng, yaw_rate_rps=yaw_rate
        )
        state = self.robot.camera_state()
        record = {
            "camera_state": {
                "position": state.position.tolist(),
                "head_yaw": state.head_yaw,
                "head_pitch": state.head_pitch,
                "tilt": state.tilt,
            },
            "camera_world": {"position": position.tolist(), "rotation": rotation.tolist()},
            "robot_pose": self.robot.pose.tolist(),
            "render": {
                "default_lighting": bool(default),
                "noise_std": noise,
                "yaw_rate_rps": yaw_rate,
                "swaying": swaying,
                "aimed_pole": aimed,
            },
            "objects": self._objects(labels, position, rotation),
        }
        return image, record

    # ----- placing -------------------------------------------------------------------------
    def _random_pose(self) -> FloatArray:
        """A pose (3,) anywhere inside the field lines, any heading."""
        dims, rng = self.scene.dimensions, self.rng
        return np.array(
            [
                rng.uniform(-dims.half_length_m, dims.half_length_m),
                rng.uniform(-dims.half_width_m, dims.half_width_m),
                rng.uniform(-math.pi, math.pi),
            ]
        )

    def _place_robots(self) -> int | None:
        """Place the other robots and ours; returns the landmark id of the pole aimed at, if
        any."""
        cfg, rng = self.config, self.rng
        for other in self.others:
            other.place(self._random_pose())
        head = np.array([rng.uniform(-_HEAD_YAW_RAD, _HEAD_YAW_RAD), rng.uniform(*_HEAD_PITCH_RAD)])
        if rng.uniform() < cfg.aim_probability:
            i = int(rng.integers(len(self.poles)))
            xy = self._aimed_position(self.poles[i])
            if xy is not None:
                to_pole = self.poles[i] - xy
                heading = (
                    math.atan2(to_pole[1], to_pole[0])
                    - head[0]
                    - rng.uniform(-_AIM_SPREAD_RAD, _AIM_SPREAD_RAD)
                )
                self.robot.place(np.array([xy[0], xy[1], heading]), head=head)
                if rng.uniform() < cfg.occluder_probability:
                    self._place_occluder(xy, self.poles[i])
                return self.codes[i].landmark_id
        self.robot.place(self._random_pose(), head=head)
        return None

    def _aimed_position(self, pole: FloatArray) -> FloatArray | None:
        """A robot position (2,) at a random distance from ``pole`` (2,) where robots stand."""
        dims, rng = self.scene.dimensions, self.rng
        half = np.array([dims.half_length_m, dims.half_width_m]) + _ROBOT_AREA_MARGIN_M
        for _ in range(50):
            distance = rng.uniform(*self.config.aim_range_m)
            angle = rng.uniform(-math.pi, math.pi)
            xy = pole + distance * np.array([math.cos(angle), math.sin(angle)])
            if np.all(np.abs(xy) <= half):
                return xy
        return None

    def _place_occluder(self, eye: FloatArray, pole: FloatArray) -> None:
        """Put the first other robot between ``eye`` (2,) and ``pole`` (2,), a little aside."""
        rng = self.rng
        along = pole - eye
        distance = float(np.linalg.norm(along))
        t = rng.uniform(0.35, 0.8)
        if t * distance < 0.35:  # not on top of our robot
            return
        side = np.array([-along[1], along[0]]) / distance
        xy = eye + t * along + rng.uniform(-0.2, 0.2) * side
        self.others[0].place(np.array([xy[0], xy[1], rng.uniform(-math.pi, math.pi)]))

    def _place_ball(self, position: FloatArray, rotation: FloatArray) -> None:
        """Ball on the ground in front of the camera or anywhere on the field."""
        rng = self.rng
        if rng.uniform() < self.config.ball_in_front_probability:
            forward = rotation[:2, 0] / max(float(np.linalg.norm(rotation[:2, 0])), 1e-9)
            azimuth = math.atan2(forward[1], forward[0]) + rng.uniform(-0.5, 0.5)
            xy = position[:2] + rng.uniform(0.3, 4.0) * np.array(
                [math.cos(azimuth), math.sin(azimuth)]
            )
        else:
            xy = self._random_pose()[:2]
        self.field.place_ball(xy)

    # ----- labels ----------------------------------------------------------------------------
    def _objects(
        self,
        labels: NDArray[np.int32],
        position: FloatArray,
        rotation: FloatArray,
    ) -> list[dict[str, Any]]:
        """One record per labelled object with at least one pixel in view.

        Each: ``class``, ``class_id``, ``box`` ``[u0, v0, u1, v1]`` (px, the labelled pixels'
        min..max), ``pixels``, ``landmark_id``, ``range_m`` and ``bearing_rad`` (poles: true,
        robot frame, else null), ``truncated`` (touches the image border),
        ``occluded_fraction`` (poles: of the in-image points on the pole's visible side, the
        fraction covered by something else; else null); poles also ``keypoint`` ``[u, v]``
        (px: the band junction on the pole axis) and ``keypoint_visible`` (inside the image
        and labelled with the pole).
        """
        bodies = self.field.bodies
        ids: dict[int, tuple[str, int | None]] = {  # body id -> (class, row in poles or None)
            body: (pole_class_name(code), k)
            for k, (code, body) in enumerate(
                zip(self.codes, self.field.pole_body_ids(), strict=True)
            )
        }
        ids |= {self.world.body(name): ("goal_post", None) for name in bodies.goal_posts}
        ids[self.world.body(bodies.ball)] = ("ball", None)
        ids |= {self.world.body(robot.name): ("robot", None) for robot in self.others}
        rb = range_bearing(self.robot.pose, self.poles)
        present, counts = np.unique(labels, return_counts=True)
        out = []
        for body, count in zip(present.tolist(), counts.tolist(), strict=True):
            if body not in ids:
                continue
            name, pole = ids[body]
            landmark_id = None if pole is None else self.codes[pole].landmark_id
            rows, cols = np.nonzero(labels == body)
            h, w = labels.shape
            record: dict[str, Any] = {
                "class": name,
                "class_id": self._class_id[name],
                "box": [int(cols.min()), int(rows.min()), int(cols.max()), int(rows.max())],
                "pixels": int(count),
                "landmark_id": landmark_id,
                "range_m": None,
                "bearing_rad": None,
                "truncated": bool(
                    cols.min() == 0 or rows.min() == 0 or cols.max() == w - 1 or rows.max() == h - 1
                ),
                "occluded_fraction": None,
            }
            if pole is not None:
                record |= self._pole_fields(labels, body, pole, position, rotation, rb)
            out.append(record)
        return out

    def _pole_fields(
        self,
        labels: NDArray[np.int32],
        body: int,
        pole: int,
        position: FloatArray,
        rotation: FloatArray,
        rb: FloatArray,
    ) -> dict[str, Any]:
        """Range, bearing, keypoint and occlusion of the pole in row ``pole`` of ``poles``
        (body id ``body``).

        ``position`` (3,) and ``rotation`` (3, 3) are the true camera pose in the field frame;
        ``rb`` (L, 2) the true range and bearing of every pole from our robot.
        """
        model = self.camera_config.model
        geometry = self.scene.poles.geometry
        xy = self.poles[pole]
        junction = np.array([xy[0], xy[1], geometry.base_top_m + geometry.band_height_m])
        [(u, v)], _ = project_points(
            ((junction - position) @ rotation)[None], model.fx, model.fy, model.cx, model.cy
        )
        col, row = round(u), round(v)
        keypoint_visible = bool(
            0 <= col < model.width
            and 0 <= row < model.height
            and np.any(labels[max(row - 1, 0) : row + 2, col] == body)  # rows may be 1 px off
        )
        return {
            "range_m": float(rb[pole, 0]),
            "bearing_rad": float(rb[pole, 1]),
            "keypoint": [float(u), float(v)],
            "keypoint_visible": keypoint_visible,
            "occluded_fraction": self._occluded_fraction(labels, body, xy, position, rotation),
        }

    def _occluded_fraction(
        self,
        labels: NDArray[np.int32],
        body: int,
        xy: FloatArray,
        position: FloatArray,
        rotation: FloatArray,
    ) -> float | None:
        """Fraction of the in-image points on the visible side of the pole at ``xy`` (2,)
        that are not labelled ``body``; None if no point is in the image."""
        model = self.camera_config.model
        geometry = self.scene.poles.geometry
        view = xy - position[:2]
        view /= np.linalg.norm(view)
        side = np.array([-view[1], view[0]])
        lateral, heights = np.meshgrid(
            np.linspace(-0.6, 0.6, 5), np.linspace(0.02, geometry.top_m - 0.02, 20)
        )
        s = lateral.ravel()[:, None]
        ground = xy + geometry.radius_m * (s * side - np.sqrt(1.0 - s**2) * view)
        points = np.column_stack([ground, heights.ravel()])
        uv, front = project_points(
            (points - position) @ rotation, model.fx, model.fy, model.cx, model.cy
        )
        inside = front & np.all(
            (uv >= 0.5) & (uv < np.array([model.width, model.height]) - 1.5), axis=1
        )
        if not inside.any():
            return None
        cols, rows = np.round(uv[inside]).astype(int).T
        return float(np.mean(labels[rows, cols] != body))


def generate(config: DatasetConfig, out: Path, images: int, seed: int, scenes: int) -> None:
    """Render ``images`` labelled frames over ``scenes`` scenes into ``out`` (see module doc).

    Scene k draws from its own generator, spawned from ``numpy.random.SeedSequence(seed)``.
    """
    if not (isinstance(images, int) and images >= 1):
        raise ValueError(f"images must be an int >= 1, got {images!r}")
    if not (isinstance(scenes, int) and 1 <= scenes <= images):
        raise ValueError(f"scenes must be an int in [1, images={images}], got {scenes!r}")
    (out / "images").mkdir(parents=True, exist_ok=True)
    streams = np.random.SeedSequence(seed).spawn(scenes)
    bounds = np.linspace(0, images, scenes + 1).round().astype(int)
    classes: tuple[str, ...] = ()
    codes: tuple[PoleCode, ...] = ()
    with open(out / "labels.jsonl", "w") as labels_file:
        for k, stream in enumerate(streams):
            sampler = FrameSampler(config, np.random.default_rng(stream))
            classes, codes = sampler.classes, sampler.codes
            try:
                for index in range(bounds[k], bounds[k + 1]):
                    image, record = sampler.sample()
                    name = f"{index:06d}.png"
                    cv2.imwrite(
                        str(out / "images" / name),
                        np.ascontiguousarray(image[:, :, ::-1]),
                        [cv2.IMWRITE_PNG_COMPRESSION, 1],
                    )
                    labels_file.write(json.dumps({"image": name, "scene": k, **record}) + "\n")
            finally:
                sampler.close()
            print(f"scene {k + 1}/{scenes}: {bounds[k + 1]} images", flush=True)
    meta = {
        "classes": list(classes),
        "pole_codes": [asdict(code) for code in codes],
        "images": images,
        "seed": seed,
        "scenes": scenes,
        "camera": asdict(CameraConfig().model),
        "config": asdict(config),
    }
    (out / "meta.json").write_text(json.dumps(meta, indent=2) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, required=True, help="output folder")
    parser.add_argument("--images", type=int, required=True, help="number of frames")
    parser.add_argument("--seed", type=int, default=0, help="seed of every random draw")
    parser.add_argument("--scenes", type=int, default=None, help="poster draws (default N/100)")
    args = parser.parse_args()
    scenes = args.scenes if args.scenes is not None else max(1, args.images // 100)
    generate(DatasetConfig(), args.out, args.images, args.seed, scenes)


if __name__ == "__main__":
    main()
