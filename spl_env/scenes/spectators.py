"""People walking about between the field and the poster boards (seed 004 names moving
spectators as the failure case of natural-landmark recognition and visual odometry).

Each spectator is a primitive person (jeans, a shirt, a head; 1.7 m tall) walking back and
forth along one side of the field, in the strip between the carpet's edge and the boards, at
the height a Nao's horizon crosses (behind the 1.2 m boards a Nao would see only heads, above
its horizon band). Shirts are coloured once, when the world is built; every episode draws each
spectator's side, place, direction and speed from the episode's generator.
"""

from __future__ import annotations

import math

import numpy as np

from perception.geometry import FloatArray
from spl_env.sim.world import BulletWorld, VisualPart

JEANS_RGBA = (0.16, 0.22, 0.42, 1.0)
SKIN_RGBA = (0.80, 0.62, 0.50, 1.0)
SPEED_SPREAD = 0.2  # speeds vary by up to this fraction around the configured one


def _person(shirt: tuple[float, float, float, float]) -> list[VisualPart]:
    """Legs, torso and head of a 1.7 m person standing on the ground, facing +x."""
    legs = VisualPart(shape="box", size=(0.12, 0.18, 0.42), position=(0, 0, 0.42), rgba=JEANS_RGBA)
    torso = VisualPart(shape="box", size=(0.13, 0.22, 0.30), position=(0, 0, 1.14), rgba=shirt)
    head = VisualPart(shape="sphere", size=(0.11,), position=(0, 0, 1.58), rgba=SKIN_RGBA)
    return [legs, torso, head]


class Spectators:
    """``count`` people walking at about ``speed_mps`` along the sides of a carpet of
    ``carpet_size_m`` (length, width; m), ``lane_m`` (m) outside its edge. ``rng`` colours their
    shirts."""

    def __init__(
        self,
        world: BulletWorld,
        count: int,
        carpet_size_m: tuple[float, float],
        lane_m: float,
        speed_mps: float,
        rng: np.random.Generator,
    ) -> None:
        self.world = world
        self.speed_mps = speed_mps
        half_l, half_w = carpet_size_m[0] / 2 + lane_m, carpet_size_m[1] / 2 + lane_m
        # each side: a point it passes through, its direction, half its length (m)
        self._sides = (
            (np.array([0.0, half_w]), np.array([1.0, 0.0]), half_l),
            (np.array([0.0, -half_w]), np.array([1.0, 0.0]), half_l),
            (np.array([half_l, 0.0]), np.array([0.0, 1.0]), half_w),
            (np.array([-half_l, 0.0]), np.array([0.0, 1.0]), half_w),
        )
        self.names = tuple(f"spectator_{k}" for k in range(count))
        for name in self.names:
            red, green, blue = (float(c) for c in rng.uniform(0.1, 0.95, 3))
            world.add_static(name, _person((red, green, blue, 1.0)), collide=False)
        self._side = np.zeros(count, dtype=np.int64)
        self._half = np.zeros(count)  # half the length of each one's side (m)
        self._along = np.zeros(count)  # position along the side (m), in [-half, half]
        self._velocity = np.zeros(count)  # along the side (m/s)

    def reset(self, rng: np.random.Generator) -> None:
        """Draw each spectator's side, place, direction and speed; put them there."""
        n = len(self.names)
        self._side = rng.integers(0, len(self._sides), size=n)
        self._half = np.array([self._sides[s][2] for s in self._side])
        self._along = rng.uniform(-self._half, self._half)
        speed = self.speed_mps * rng.uniform(1 - SPEED_SPREAD, 1 + SPEED_SPREAD, size=n)
        self._velocity = speed * rng.choice([-1.0, 1.0], size=n)
        self._place()

    def move(self, dt_s: float) -> None:
        """Walk on for ``dt_s`` (s), turning back at the end of the side."""
        if not self.names:
            return
        along = self._along + self._velocity * dt_s
        turned = np.abs(along) > self._half
        self._velocity[turned] = -self._velocity[turned]
        self._along = np.clip(along, -self._half, self._half)
        self._place()

    @property
    def positions(self) -> FloatArray:
        """(N, 2) ground positions (m, field frame)."""
        return np.array(
            [
                self._sides[s][0] + a * self._sides[s][1]
                for s, a in zip(self._side, self._along, strict=True)
            ]
        ).reshape(-1, 2)

    def _place(self) -> None:
        for name, xy, side, v in zip(
            self.names, self.positions, self._side, self._velocity, strict=True
        ):
            direction = self._sides[side][1] * math.copysign(1.0, v)
            self.world.set_pose(name, (xy[0], xy[1], 0.0), math.atan2(direction[1], direction[0]))
