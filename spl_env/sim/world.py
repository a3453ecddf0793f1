"""BulletWorld: the one module that talks to PyBullet.

Each world owns its own ``p.DIRECT`` physics client and passes ``physicsClientId`` on every call,
so several worlds live side by side in one process. Bodies are addressed by name.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pybullet as p
from numpy.typing import NDArray

from perception.geometry import FloatArray
from perception.validation import check_finite, check_positive, finite_points, finite_vector

MAX_PARTS_PER_BODY = 16  # PyBullet's shape arrays crash beyond 16 shapes


@dataclass(frozen=True, kw_only=True)
class VisualPart:
    """One primitive of a compound static body: a box (half extents) or a cylinder/sphere.

    ``shape`` is ``"box"``, ``"cylinder"`` or ``"sphere"``; ``size`` is the box half extents
    (3,) or ``(radius, length)`` for cylinders or ``(radius,)`` for spheres (m); ``position`` (3,)
    is relative to the body origin; ``yaw`` (rad) rotates the part about z; ``rgba`` in [0, 1].
    """

    shape: str
    size: tuple[float, ...]
    position: tuple[float, float, float]
    rgba: tuple[float, float, float, float]
    yaw: float = 0.0


@dataclass(frozen=True, kw_only=True)
class Lighting:
    """Tiny-renderer lighting of a frame: direction (3,) towards the light, colour, coefficients."""

    direction: tuple[float, float, float] = (0.3, 0.2, 1.0)
    colour: tuple[float, float, float] = (1.0, 1.0, 1.0)
    ambient: float = 0.6
    diffuse: float = 0.4
    specular: float = 0.05


class BulletWorld:
    """A PyBullet ``DIRECT`` client with named bodies, stepping, ray casts and rendering."""

    def __init__(self, *, time_step_s: float, gravity_mps2: float = 9.81) -> None:
        if not (0.0 < time_step_s <= 0.1):
            raise ValueError(f"time_step_s must be in (0, 0.1] s, got {time_step_s}")
        self._client: int | None = p.connect(p.DIRECT)
        self._bodies: dict[str, int] = {}
        self.time_step_s = time_step_s
        p.setGravity(0.0, 0.0, -gravity_mps2, physicsClientId=self.client)
        p.setTimeStep(time_step_s, physicsClientId=self.client)

    @property
    def client(self) -> int:
        """The PyBullet client id; raises after :meth:`close`."""
        if self._client is None:
            raise RuntimeError("BulletWorld is closed")
        return self._client

    # ----- bodies -------------------------------------------------------------------------
    def _register(self, name: str, body_id: int) -> int:
        if name in self._bodies:
            raise ValueError(f"body name {name!r} is already used")
        self._bodies[name] = body_id
        return body_id

    def body(self, name: str) -> int:
        """The body id of ``name``."""
        return self._bodies[name]

    def add_static(
        self,
        name: str,
        parts: Sequence[VisualPart],
        *,
        collide: bool = True,
        base_position: Sequence[float] = (0.0, 0.0, 0.0),
    ) -> int:
        """A fixed compound body of primitives; with ``collide`` each part also collides."""
        vis = self._shape_array(parts, visual=True)
        col = self._shape_array(parts, visual=False) if collide else -1
        body_id = p.createMultiBody(
            baseMass=0.0,
            baseCollisionShapeIndex=col,
            baseVisualShapeIndex=vis,
            basePosition=list(base_position),
            physicsClientId=self.client,
        )
        return self._register(name, body_id)

    def add_sphere(
        self,
        name: str,
        *,
        radius_m: float,
        mass_kg: float,
        position: Sequence[float],
        rgba: Sequence[float],
        rolling_friction: float,
        restitution: float,
    ) -> int:
        """A dynamic sphere (the ball)."""
        col = p.createCollisionShape(p.GEOM_SPHERE, radius=radius_m, physicsClientId=self.client)
        vis = p.createVisualShape(
            p.GEOM_SPHERE, radius=radius_m, rgbaColor=list(rgba), physicsClientId=self.client
        )
        body_id = p.createMultiBody(
            baseMass=mass_kg,
            baseCollisionShapeIndex=col,
            baseVisualShapeIndex=vis,
            basePosition=list(position),
            physicsClientId=self.client,
        )
        p.changeDynamics(
            body_id,
            -1,
            rollingFriction=rolling_friction,
            spinningFriction=rolling_friction,
            restitution=restitution,
            lateralFriction=0.6,
            linearDamping=0.0,
            angularDamping=0.0,
            physicsClientId=self.client,
        )
        return self._register(name, body_id)

    def add_articulated(
        self,
        name: str,
        base_parts: Sequence[VisualPart],
        links: Sequence[LinkSpec],
    ) -> int:
        """A kinematic (mass 0) body with revolute links, e.g. a robot with a head."""
        vis = self._shape_array(base_parts, visual=True)
        col = self._shape_array(base_parts, visual=False)
        link_vis = [
            self._shape_array(link.parts, visual=True) if link.parts else -1 for link in links
        ]
        link_col = [
            self._shape_array(link.parts, visual=False) if link.parts else -1 for link in links
        ]
        body_id = p.createMultiBody(
            baseMass=0.0,
            baseCollisionShapeIndex=col,
            baseVisualShapeIndex=vis,
            basePosition=[0.0, 0.0, 0.0],
            linkMasses=[0.0] * len(links),
            linkCollisionShapeIndices=link_col,
            linkVisualShapeIndices=link_vis,
            linkPositions=[list(link.offset) for link in links],
            linkOrientations=[[0.0, 0.0, 0.0, 1.0]] * len(links),
            linkInertialFramePositions=[[0.0, 0.0, 0.0]] * len(links),
            linkInertialFrameOrientations=[[0.0, 0.0, 0.0, 1.0]] * len(links),
            linkParentIndices=[link.parent for link in links],
            linkJointTypes=[p.JOINT_REVOLUTE] * len(links),
            linkJointAxis=[list(link.axis) for link in links],
            physicsClientId=self.client,
        )
        return self._register(name, body_id)

    def _shape_array(self, parts: Sequence[VisualPart], *, visual: bool) -> int:
        if not 1 <= len(parts) <= MAX_PARTS_PER_BODY:
            raise ValueError(
                f"parts must hold 1 to {MAX_PARTS_PER_BODY} shapes per body, got {len(parts)}"
            )
        kinds = {"box": p.GEOM_BOX, "cylinder": p.GEOM_CYLINDER, "sphere": p.GEOM_SPHERE}
        for part in parts:
            if part.shape not in kinds:
                raise ValueError(
                    f"VisualPart.shape must be one of {sorted(kinds)}, got {part.shape!r}"
                )
        shape_types = [kinds[part.shape] for part in parts]
        half_extents = [
            list(part.size) if part.shape == "box" else [0.0, 0.0, 0.0] for part in parts
        ]
        radii = [part.size[0] if part.shape != "box" else 0.0 for part in parts]
        lengths = [part.size[1] if part.shape == "cylinder" else 0.0 for part in parts]
        positions = [list(part.position) for part in parts]
        orientations = [list(p.getQuaternionFromEuler([0.0, 0.0, part.yaw])) for part in parts]
        if visual:
            return int(
                p.createVisualShapeArray(
                    shapeTypes=shape_types,
                    halfExtents=half_extents,
                    radii=radii,
                    lengths=lengths,
                    rgbaColors=[list(part.rgba) for part in parts],
                    visualFramePositions=positions,
                    visualFrameOrientations=orientations,
                    physicsClientId=self.client,
                )
            )
        return int(
            p.createCollisionShapeArray(
                shapeTypes=shape_types,
                halfExtents=half_extents,
                radii=radii,
                lengths=lengths,
                collisionFramePositions=positions,
                collisionFrameOrientations=orientations,
                physicsClientId=self.client,
            )
        )

    def add_static_prism(
        self,
        name: str,
        polygon: FloatArray,
        height_m: float,
        rgba: Sequence[float],
        base_z_m: float = 0.0,
    ) -> int:
        """A fixed vertical prism over ``polygon``, as a static concave triangle mesh.

        ``polygon`` (N, 2), N >= 3, is a simple plan-view outline in the world frame (m), convex
        or concave, either winding; the prism stands from ``base_z_m`` to ``base_z_m +
        height_m``. Its side faces and two caps become one triangle mesh (vertices and indices)
        for both collision and visual shapes, mass 0: rays hit the faces themselves, with no
        collision margin. Collinear vertices are dropped; a self-intersecting outline raises.
        """
        outline = finite_points(polygon, "polygon", 3)
        check_positive("", "height_m", height_m)
        check_finite("", "base_z_m", base_z_m)
        colour = finite_vector(rgba, "rgba", 4)
        outline = _simple_ccw_polygon(outline)
        n = len(outline)
        caps = _ear_clip(outline)  # (n - 2, 3) counter-clockwise seen from above
        bottom = np.column_stack([outline, np.zeros(n)])
        top = np.column_stack([outline, np.full(n, float(height_m))])
        # collision: 2n shared vertices, bottom ring then top ring; faces wound outwards
        i = np.arange(n)
        j = (i + 1) % n
        sides = np.concatenate([np.column_stack([i, j, n + j]), np.column_stack([i, n + j, n + i])])
        col_indices = np.concatenate([sides, caps + n, caps[:, ::-1]])
        col = p.createCollisionShape(
            p.GEOM_MESH,
            vertices=np.concatenate([bottom, top]).tolist(),
            indices=col_indices.ravel().tolist(),
            physicsClientId=self.client,
        )
        # visual: each side face has its own four vertices, so that its normal is flat
        edge = outline[j] - outline[i]
        side_normals = np.column_stack([edge[:, 1], -edge[:, 0], np.zeros(n)])
        side_normals /= np.linalg.norm(side_normals, axis=1, keepdims=True)
        quads = np.stack([bottom[i], bottom[j], top[j], top[i]], axis=1).reshape(-1, 3)
        base = 4 * i[:, None]
        quad_faces = np.concatenate([base + np.array([0, 1, 2]), base + np.array([0, 2, 3])])
        vertices = np.concatenate([quads, top, bottom])
        normals = np.concatenate(
            [
                np.repeat(side_normals, 4, axis=0),
                np.tile([0.0, 0.0, 1.0], (n, 1)),
                np.tile([0.0, 0.0, -1.0], (n, 1)),
            ]
        )
        vis_indices = np.concatenate([quad_faces, caps + 4 * n, caps[:, ::-1] + 5 * n])
        vis = p.createVisualShape(
            p.GEOM_MESH,
            vertices=vertices.tolist(),
            indices=vis_indices.ravel().tolist(),
            normals=normals.tolist(),
            rgbaColor=colour.tolist(),
            physicsClientId=self.client,
        )
        if col < 0 or vis < 0:
            raise RuntimeError(f"PyBullet could not create the prism {name!r}")
        body_id = p.createMultiBody(
            baseMass=0.0,
            baseCollisionShapeIndex=col,
            baseVisualShapeIndex=vis,
            basePosition=[0.0, 0.0, float(base_z_m)],
            physicsClientId=self.client,
        )
        return self._register(name, body_id)

    def set_texture(self, name: str, texture_path: str) -> None:
        """Paint ``texture_path`` (PNG) on body ``name``'s base visual."""
        tex = p.loadTexture(texture_path, physicsClientId=self.client)
        p.changeVisualShape(self.body(name), -1, textureUniqueId=tex, physicsClientId=self.client)

    # ----- state --------------------------------------------------------------------------
    def set_pose(
        self,
        name: str,
        position: Sequence[float],
        yaw: float,
        roll: float = 0.0,
        pitch: float = 0.0,
    ) -> None:
        """Teleport body ``name`` to ``position`` (3,) with the given Euler angles (rad)."""
        quat = p.getQuaternionFromEuler([roll, pitch, yaw])
        p.resetBasePositionAndOrientation(
            self.body(name), list(position), quat, physicsClientId=self.client
        )

    def position(self, name: str) -> FloatArray:
        """World position (3,) of body ``name``'s base."""
        pos, _ = p.getBasePositionAndOrientation(self.body(name), physicsClientId=self.client)
        return np.asarray(pos, dtype=np.float64)

    def velocity(self, name: str) -> FloatArray:
        """World linear velocity (3,) (m/s) of body ``name``'s base."""
        linear, _ = p.getBaseVelocity(self.body(name), physicsClientId=self.client)
        return np.asarray(linear, dtype=np.float64)

    def set_velocity(
        self, name: str, linear: Sequence[float], angular: Sequence[float] = (0.0, 0.0, 0.0)
    ) -> None:
        """Set body ``name``'s linear (m/s) and angular (rad/s) velocity."""
        p.resetBaseVelocity(
            self.body(name), list(linear), list(angular), physicsClientId=self.client
        )

    def set_joint(self, name: str, joint_index: int, angle: float) -> None:
        """Set a revolute joint of body ``name`` to ``angle`` (rad)."""
        p.resetJointState(self.body(name), joint_index, angle, physicsClientId=self.client)

    def step(self, n_substeps: int) -> None:
        """Advance the physics by ``n_substeps`` time steps."""
        for _ in range(n_substeps):
            p.stepSimulation(physicsClientId=self.client)

    def save_state(self) -> int:
        """Snapshot of the whole physics state, for exact resets."""
        return int(p.saveState(physicsClientId=self.client))

    def restore_state(self, state_id: int) -> None:
        """Return to a snapshot from :meth:`save_state`."""
        p.restoreState(stateId=state_id, physicsClientId=self.client)

    # ----- sensing ------------------------------------------------------------------------
    def ray_test(
        self, starts: FloatArray, ends: FloatArray
    ) -> tuple[FloatArray, NDArray[np.int64]]:
        """Batched ray casts: (N, 3) starts and ends -> hit fractions (N,) and body ids (N,).

        A fraction of 1.0 with body id -1 means no hit.
        """
        n = len(starts)
        fractions = np.ones(n)
        ids = np.full(n, -1, dtype=np.int64)
        batch = p.MAX_RAY_INTERSECTION_BATCH_SIZE
        for lo in range(0, n, batch):
            hits = p.rayTestBatch(
                starts[lo : lo + batch].tolist(),
                ends[lo : lo + batch].tolist(),
                physicsClientId=self.client,
            )
            for i, hit in enumerate(hits):
                ids[lo + i] = hit[0]
                fractions[lo + i] = hit[2] if hit[0] >= 0 else 1.0
        return fractions, ids

    def render(
        self,
        *,
        width: int,
        height: int,
        view: Sequence[float],
        projection: Sequence[float],
        lighting: Lighting,
    ) -> tuple[NDArray[np.uint8], NDArray[np.int32]]:
        """Tiny-renderer image (H, W, 3) uint8 RGB and (H, W) body-id labels (-1 = background)."""
        _, _, rgba, _, seg = p.getCameraImage(
            width,
            height,
            viewMatrix=list(view),
            projectionMatrix=list(projection),
            renderer=p.ER_TINY_RENDERER,
            shadow=0,
            lightDirection=list(lighting.direction),
            lightColor=list(lighting.colour),
            lightAmbientCoeff=lighting.ambient,
            lightDiffuseCoeff=lighting.diffuse,
            lightSpecularCoeff=lighting.specular,
            physicsClientId=self.client,
        )
        rgb = np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3]
        labels = np.asarray(seg, dtype=np.int32).reshape(height, width)
        return np.ascontiguousarray(rgb), labels

    def close(self) -> None:
        """Disconnect; safe to call more than once."""
        if self._client is not None:
            p.disconnect(physicsClientId=self._client)
            self._client = None


def _simple_ccw_polygon(points: FloatArray) -> FloatArray:
    """``points`` (N, 2) without collinear vertices, counter-clockwise; raises unless simple."""
    prev, nxt = np.roll(points, 1, axis=0), np.roll(points, -1, axis=0)
    turn = _cross(points - prev, nxt - points)
    scale = float(np.abs(points).max()) + 1.0
    points = points[np.abs(turn) > 1e-12 * scale**2]
    area = 0.5 * float(_cross(points, np.roll(points, -1, axis=0)).sum()) if len(points) else 0.0
    if len(points) < 3 or area == 0.0:
        raise ValueError(
            f"polygon must be simple and enclose an area, got {len(points)} non-collinear vertices"
        )
    points = points if area > 0 else points[::-1]
    a, b = points, np.roll(points, -1, axis=0)
    n = len(points)
    for k in range(n):  # every edge against every later edge that does not share a vertex
        others = np.arange(k + 2, n if k > 0 else n - 1)
        if len(others) and _segments_cross(a[k], b[k], a[others], b[others]).any():
            raise ValueError(f"polygon must be simple, but its edge {k} crosses another edge")
    return np.ascontiguousarray(points)


def _cross(u: FloatArray, v: FloatArray) -> FloatArray:
    """z component of the cross products of 2-D vectors (..., 2) x (..., 2)."""
    return np.asarray(u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0])


def _segments_cross(a: FloatArray, b: FloatArray, c: FloatArray, d: FloatArray) -> FloatArray:
    """Whether segment a-b (2,) meets each segment c-d (M, 2), touching included: (M,) bool."""
    d1, d2 = _cross(b - a, c - a), _cross(b - a, d - a)
    d3, d4 = _cross(d - c, a - c), _cross(d - c, b - c)
    return np.asarray((d1 * d2 <= 0.0) & (d3 * d4 <= 0.0))


def _ear_clip(points: FloatArray) -> NDArray[np.int64]:
    """Triangles (N - 2, 3) of vertex indices covering the simple counter-clockwise polygon
    ``points`` (N, 2), each counter-clockwise (ear clipping)."""
    remaining = list(range(len(points)))
    triangles = []
    while len(remaining) > 3:
        m = len(remaining)
        for k in range(m):
            i0, i1, i2 = remaining[k - 1], remaining[k], remaining[(k + 1) % m]
            a, b, c = points[i0], points[i1], points[i2]
            if _cross(b - a, c - b) <= 0.0:  # a reflex corner is no ear
                continue
            rest = points[[r for r in remaining if r not in (i0, i1, i2)]]
            inside = (
                (_cross(b - a, rest - a) >= 0.0)
                & (_cross(c - b, rest - b) >= 0.0)
                & (_cross(a - c, rest - c) >= 0.0)
            )
            if not inside.any():
                triangles.append((i0, i1, i2))
                del remaining[k]
                break
        else:
            raise ValueError("polygon must be simple, but it has no ear left to clip")
    triangles.append((remaining[0], remaining[1], remaining[2]))
    return np.asarray(triangles, dtype=np.int64)


@dataclass(frozen=True, kw_only=True)
class LinkSpec:
    """A revolute link of an articulated body: parent index (0 = base), joint offset and axis."""

    parent: int
    offset: tuple[float, float, float]
    axis: tuple[float, float, float]
    parts: tuple[VisualPart, ...] = ()
