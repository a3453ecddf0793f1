"""The robot's top camera: renders the world and applies image-formation effects.

A frame is one ``getCameraImage`` call at the camera's resolution (tiny renderer, no shadows),
then exposure, one bright side as from a window, motion blur and sensor noise in numpy. The
label image holds the body id seen at each pixel, for automatic labelling.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray
from perception.types import CameraModel
from perception.validation import (
    check_bool,
    check_in_interval,
    check_nested_configs,
    check_positive,
    check_reals,
)
from spl_env.sim.world import BulletWorld, Lighting


@dataclass(frozen=True, kw_only=True)
class LightingRandomisation:
    """Ranges drawn once per episode when lighting randomisation is on."""

    ambient: tuple[float, float] = (0.45, 0.8)  # tiny-renderer ambient coefficient
    diffuse: tuple[float, float] = (0.2, 0.55)  # tiny-renderer diffuse coefficient
    colour_jitter: float = 0.12  # per-channel light colour in [1 - j, 1]
    exposure: tuple[float, float] = (0.75, 1.25)  # image gain
    window_probability: float = 0.5  # chance that one side of the field has a bright window
    window_strength: tuple[float, float] = (
        0.3,
        0.7,
    )  # added brightness (fraction of 255) facing it

    def __post_init__(self) -> None:
        owner = "LightingRandomisation"
        for name in ("ambient", "diffuse", "exposure", "window_strength"):
            check_reals(owner, name, getattr(self, name), 2)
            lo, hi = getattr(self, name)
            if not 0 <= lo <= hi:
                raise ValueError(f"{owner}.{name} must be 0 <= lo <= hi, got {(lo, hi)}")
        check_in_interval(owner, "colour_jitter", self.colour_jitter, 0.0, 1.0, low_inclusive=True)
        check_in_interval(
            owner,
            "window_probability",
            self.window_probability,
            0.0,
            1.0,
            low_inclusive=True,
            high_inclusive=True,
        )


@dataclass(frozen=True, kw_only=True)
class CameraConfig:
    """Camera intrinsics, clipping planes and image-formation effects."""

    model: CameraModel = field(default_factory=CameraModel)
    near_m: float = 0.01  # near clipping plane
    far_m: float = 20.0  # far clipping plane
    noise_std: float = 2.0  # Gaussian sensor noise (8-bit levels)
    exposure_time_s: float = 0.01  # for motion blur from head and body turning
    randomise_lighting: bool = False
    randomisation: LightingRandomisation = field(default_factory=LightingRandomisation)

    def __post_init__(self) -> None:
        check_nested_configs(self)
        owner = "CameraConfig"
        check_positive(owner, "near_m", self.near_m)
        check_positive(owner, "far_m", self.far_m)
        if not self.near_m < self.far_m:
            raise ValueError(
                f"CameraConfig needs 0 < near_m < far_m, got {self.near_m}, {self.far_m}"
            )
        check_positive(owner, "noise_std", self.noise_std, allow_zero=True)
        check_positive(owner, "exposure_time_s", self.exposure_time_s, allow_zero=True)
        check_bool(owner, "randomise_lighting", self.randomise_lighting)


@dataclass(frozen=True, kw_only=True)
class EpisodeLighting:
    """The lighting of one episode: renderer lighting, exposure gain and the window (if any).

    ``window_direction`` is a unit (2,) field-frame direction towards the window, or ``None``.
    """

    lighting: Lighting
    exposure: float
    window_direction: FloatArray | None
    window_strength: float

    @staticmethod
    def default() -> EpisodeLighting:
        """Even lighting, no window."""
        return EpisodeLighting(
            lighting=Lighting(), exposure=1.0, window_direction=None, window_strength=0.0
        )

    @staticmethod
    def sample(r: LightingRandomisation, rng: np.random.Generator) -> EpisodeLighting:
        """Draw an episode's lighting from the ranges in ``r``."""
        azimuth = rng.uniform(0, 2 * math.pi)
        elevation = rng.uniform(math.radians(35), math.radians(85))
        direction = (
            math.cos(elevation) * math.cos(azimuth),
            math.cos(elevation) * math.sin(azimuth),
            math.sin(elevation),
        )
        colour = tuple(float(c) for c in rng.uniform(1 - r.colour_jitter, 1.0, size=3))
        lighting = Lighting(
            direction=direction,
            colour=(colour[0], colour[1], colour[2]),
            ambient=float(rng.uniform(*r.ambient)),
            diffuse=float(rng.uniform(*r.diffuse)),
        )
        window = rng.uniform() < r.window_probability
        side = rng.uniform(0, 2 * math.pi)
        return EpisodeLighting(
            lighting=lighting,
            exposure=float(rng.uniform(*r.exposure)),
            window_direction=np.array([math.cos(side), math.sin(side)]) if window else None,
            window_strength=float(rng.uniform(*r.window_strength)) if window else 0.0,
        )


class Camera:
    """Renders what the camera sees from a given field-frame pose."""

    def __init__(self, config: CameraConfig) -> None:
        self.config = config
        m = config.model
        self._projection = _projection_matrix(m, config.near_m, config.far_m)

    def render(
        self,
        world: BulletWorld,
        position: FloatArray,
        rotation: FloatArray,
        lighting: EpisodeLighting,
        rng: np.random.Generator,
        yaw_rate_rps: float = 0.0,
    ) -> tuple[NDArray[np.uint8], NDArray[np.int32]]:
        """Image (H, W, 3) uint8 RGB and (H, W) body-id labels seen from the camera pose.

        Blur and noise are worked in floats and the result cut to uint8 (truncated, not
        rounded: with noise on, a frame is about half a grey level darker than the renderer's).

        ``position`` (3,) and ``rotation`` (3, 3) are the camera frame in the field frame;
        ``yaw_rate_rps`` is the camera's turn rate, for motion blur.
        """
        m = self.config.model
        forward, up = rotation[:, 0], rotation[:, 2]
        view = _view_matrix(position, forward, up)
        rgb, labels = world.render(
            width=m.width,
            height=m.height,
            view=view,
            projection=self._projection,
            lighting=lighting.lighting,
        )
        image = np.multiply(rgb, np.float32(lighting.exposure), dtype=np.float32)
        if lighting.window_direction is not None:
            image = _window_glare(
                image, forward, lighting.window_direction, lighting.window_strength, m
            )
        blur_px = blur_length_px(yaw_rate_rps, self.config.exposure_time_s, m.fx)
        if blur_px > 0:
            k = round(blur_px)
            image = np.asarray(cv2.blur(image, (k, 1)), dtype=np.float32)
        if self.config.noise_std > 0:
            noise = rng.standard_normal(size=image.shape, dtype=np.float32)
            noise *= np.float32(self.config.noise_std)
            image += noise
        return np.clip(image, 0, 255, out=image).astype(np.uint8), labels


def blur_length_px(yaw_rate_rps: float, exposure_time_s: float, fx: float) -> float:
    """Horizontal motion blur (px) of a frame, as :class:`Camera` applies it: none below 1.5 px."""
    blur = abs(yaw_rate_rps) * exposure_time_s * fx
    return blur if blur >= 1.5 else 0.0


def _window_glare(
    image: NDArray[np.float32],
    forward: FloatArray,
    window_direction: FloatArray,
    strength: float,
    model: CameraModel,
) -> NDArray[np.float32]:
    """Wash out the image when looking towards the window, brighter on the window's side."""
    heading = forward[:2] / max(float(np.linalg.norm(forward[:2])), 1e-9)
    facing = float(heading @ window_direction)
    if facing <= 0:
        return image
    # which image side the window is on: its direction's component along the camera's left
    left = np.array([-heading[1], heading[0]])
    side = float(left @ window_direction)
    ramp = np.linspace(1.0 + side, 1.0 - side, model.width, dtype=np.float32) / 2.0
    glare = 255.0 * strength * facing * ramp
    return image * (1.0 - 0.5 * strength * facing) + glare[None, :, None]


def _view_matrix(eye: FloatArray, forward: FloatArray, up: FloatArray) -> list[float]:
    """Column-major OpenGL view matrix looking along ``forward`` with ``up`` (both (3,))."""
    f = forward / np.linalg.norm(forward)
    s = np.cross(f, up)
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = s, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m.T.reshape(-1).tolist()


def _projection_matrix(model: CameraModel, near: float, far: float) -> list[float]:
    """Column-major OpenGL perspective matrix matching the pinhole ``model``."""
    m = np.zeros((4, 4))
    m[0, 0] = 2 * model.fx / model.width
    m[1, 1] = 2 * model.fy / model.height
    m[2, 2] = -(far + near) / (far - near)
    m[2, 3] = -2 * far * near / (far - near)
    m[3, 2] = -1.0
    return m.T.reshape(-1).tolist()
