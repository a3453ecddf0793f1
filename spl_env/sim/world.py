"""BulletWorld: the one module that talks to PyBullet.

Each world owns its own ``p.DIRECT`` physics client and passes ``physicsClientId`` on every call,
so several worlds live side by side in one process. Bodies are addressed by name.

Stepping skips the physics while it has nothing to do: when every dynamic body (the ball) lies
at rest in contact and no body moved by hand (a robot, a spectator) comes near it, a PyBullet
step leaves the world as it was (to about 1e-19 m), and the 10 steps of a control step would
cost more than all the rest of a geometric-mode env step.
"""

from __future__ import annotations

import hashlib
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pybullet as p
from numpy.typing import NDArray

from perception.geometry import FloatArray
from perception.validation import check_finite, check_positive, finite_points, finite_vector

MAX_PARTS_PER_BODY = 16  # PyBullet's shape arrays crash beyond 16 shapes
REST_SPEED = 1e-6  # m/s and rad/s: a dynamic body this slow in contact lies at rest
CONTACT_CLEAR_HEIGHT_M = 1000.0  # m: a dynamic body this high touches nothing
REST_CLEARANCE_M = 0.05  # a moved body this near a resting one could touch it in a step
# Bullet's collision filter groups: bit 0 marks dynamic bodies and bit 1 static ones (its
# defaults); a body that ray tests pass through gets a private bit from those above.
STATIC_FILTER = 1 << 1
PRIVATE_FILTER_BITS = tuple(1 << k for k in range(2, 31))


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
class TriangleMesh:
    """Triangles of a static visual mesh, in its body's frame (m).

    ``vertices`` (N, 3) and their unit ``normals`` (N, 3); ``triangles`` (M, 3) vertex indices,
    each counter-clockwise seen from the side that shows (the tiny renderer culls back faces);
    ``uvs`` (N, 2) texture coordinates in [0, 1], or None for an untextured mesh.
    """

    vertices: FloatArray
    triangles: NDArray[np.int64]
    normals: FloatArray
    uvs: FloatArray | None = None

    def __post_init__(self) -> None:
        n = len(self.vertices)
        if n == 0 or self.vertices.shape != (n, 3) or not np.isfinite(self.vertices).all():
            raise ValueError(
                f"TriangleMesh.vertices must be (N, 3) finite, got {self.vertices.shape}"
            )
        if self.normals.shape != (n, 3) or not np.allclose(np.linalg.norm(self.normals, axis=1), 1):
            raise ValueError(
                f"TriangleMesh.normals must be ({n}, 3) unit vectors, got {self.normals.shape}"
            )
        t = self.triangles
        if t.ndim != 2 or t.shape[1] != 3 or len(t) == 0 or t.min() < 0 or t.max() >= n:
            raise ValueError(
                f"TriangleMesh.triangles must be (M, 3) indices in [0, {n}), got shape {t.shape}"
            )
        uvs = self.uvs
        if uvs is not None and (uvs.shape != (n, 2) or not ((uvs >= 0) & (uvs <= 1)).all()):
            raise ValueError(f"TriangleMesh.uvs must be ({n}, 2) in [0, 1], got {uvs.shape}")

    @staticmethod
    def concatenate(meshes: Sequence[TriangleMesh]) -> TriangleMesh:
        """One mesh holding all of ``meshes`` (at least one, all untextured)."""
        if any(m.uvs is not None for m in meshes):
            raise ValueError("TriangleMesh.concatenate joins untextured meshes only")
        offsets = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
        return TriangleMesh(
            vertices=np.concatenate([m.vertices for m in meshes]),
            triangles=np.concatenate(
                [m.triangles + k for m, k in zip(meshes, offsets, strict=True)]
            ),
            normals=np.concatenate([m.normals for m in meshes]),
        )


@dataclass(frozen=True, kw_only=True)
class PaintedFloor:
    """A floor rectangle in the plane z = 0, centred on the world origin, that
    :meth:`BulletWorld.render` paints into each frame rather than have the tiny renderer shade it.

    Flat and untextured, it comes out of the renderer in one colour per lighting: so each frame
    paints that colour where the pixel's ray meets the rectangle before anything the renderer
    drew (by the frame's depth buffer), as its depth test would have; a floor covering half the
    frame costs the renderer about as much as everything else in it.
    ``body`` is its body id (for the labels), ``half_extents`` (2,) its half length and width
    (m), ``rgba`` its colour in [0, 1].
    """

    body: int
    half_extents: tuple[float, float]
    rgba: tuple[float, float, float, float]


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
        # every client this world connected, disconnected by close() or, for a world dropped
        # unclosed (or an env whose construction failed), when it is collected
        self._connected = [self._client]
        self._disconnect = weakref.finalize(self, _disconnect_all, self._connected)
        self._bodies: dict[str, int] = {}
        self._floor: PaintedFloor | None = None
        # the lighting the floor was last shaded under, and its RGB (3,) then
        self._floor_colour_for: tuple[Lighting, NDArray[np.uint8]] | None = None
        self._probe: int | None = None  # a client holding the floor alone, to shade it
        self._dynamic: list[int] = []  # bodies with mass, which the physics moves
        self._moved: set[int] = set()  # bodies moved by hand (set_pose, set_joints) ever
        self._disturbed = False  # a dynamic body was set by hand since the last physics step
        # body id -> the joint angles set_joints last gave it, while nothing else can have
        # moved its joints since (a physics step or a restored snapshot forgets them all)
        self._joints_set: dict[int, list[list[float]]] = {}
        self._filter_bits: dict[int, int] = {}  # body id -> its private collision filter group
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

    def add_static_mesh(
        self,
        name: str,
        mesh: TriangleMesh,
        rgba: Sequence[float],
        *,
        collision: Sequence[VisualPart] = (),
        base_position: Sequence[float] = (0.0, 0.0, 0.0),
    ) -> int:
        """A fixed body at ``base_position`` (3,) seen as one triangle ``mesh`` (body frame) of
        colour ``rgba``; it collides as the primitives ``collision`` (their colours unused), or
        not at all."""
        vis = p.createVisualShape(
            p.GEOM_MESH,
            rgbaColor=list(finite_vector(rgba, "rgba", 4)),
            physicsClientId=self.client,
            **_mesh_lists(mesh),
        )
        if vis < 0:
            raise RuntimeError(f"PyBullet could not create the mesh {name!r}")
        col = self._shape_array(collision, visual=False) if collision else -1
        body_id = p.createMultiBody(
            baseMass=0.0,
            baseCollisionShapeIndex=col,
            baseVisualShapeIndex=vis,
            basePosition=list(finite_vector(base_position, "base_position", 3)),
            physicsClientId=self.client,
        )
        return self._register(name, body_id)

    def add_painted_floor(
        self,
        name: str,
        half_extents: tuple[float, float],
        rgba: tuple[float, float, float, float],
        *,
        collision: Sequence[VisualPart],
    ) -> int:
        """The world's :class:`PaintedFloor` (one at most): a fixed body that collides as the
        primitives ``collision`` and that :meth:`render` paints, ``half_extents`` (2,) (m)."""
        if self._floor is not None:
            raise ValueError("this world has a painted floor already")
        check_positive("", "half_extents[0]", half_extents[0])
        check_positive("", "half_extents[1]", half_extents[1])
        # the renderer skips a shape of alpha 0; without any, it would draw the collision shape
        unseen = p.createVisualShape(
            p.GEOM_BOX,
            halfExtents=[half_extents[0], half_extents[1], 0.01],
            rgbaColor=[*rgba[:3], 0.0],
            physicsClientId=self.client,
        )
        body_id = p.createMultiBody(
            baseMass=0.0,
            baseCollisionShapeIndex=self._shape_array(collision, visual=False),
            baseVisualShapeIndex=unseen,
            physicsClientId=self.client,
        )
        self._floor = PaintedFloor(body=body_id, half_extents=half_extents, rgba=rgba)
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
        self._dynamic.append(body_id)
        self._disturbed = True
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
        body_id = self.body(name)
        p.resetBasePositionAndOrientation(
            body_id, list(position), quat, physicsClientId=self.client
        )
        self._touched(body_id)

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
        body_id = self.body(name)
        p.resetBaseVelocity(body_id, list(linear), list(angular), physicsClientId=self.client)
        self._touched(body_id)

    def set_joints(self, name: str, angles: Sequence[float]) -> None:
        """Set the revolute joints ``0 .. len(angles) - 1`` of body ``name`` to ``angles``
        (rad), at rest. Joints that already hold these angles, set here with nothing able to
        move them since, are left as they are (a scripted robot's head that does not turn)."""
        body_id = self.body(name)
        targets = [[float(angle)] for angle in angles]
        if self._joints_set.get(body_id) != targets:
            p.resetJointStatesMultiDof(
                body_id, list(range(len(angles))), targets, physicsClientId=self.client
            )
            self._joints_set[body_id] = targets
        self._touched(body_id)

    def _touched(self, body_id: int) -> None:
        """Note that ``body_id`` was set by hand: a mover, or a dynamic body to simulate."""
        if body_id in self._dynamic:
            self._disturbed = True
        else:
            self._moved.add(body_id)

    def step(self, n_substeps: int) -> None:
        """Advance the physics by ``n_substeps`` time steps, or by none while :meth:`at_rest`
        (the steps would change nothing measurable: a ball at rest on the carpet stays put to the
        last bit; one at rest against a post drifts by about 1e-19 m a step, which a later push
        can grow to 1e-8 m)."""
        if self.at_rest():
            return
        for _ in range(n_substeps):
            p.stepSimulation(physicsClientId=self.client)
        self._disturbed = False
        self._joints_set.clear()  # the step may have moved joints

    def at_rest(self) -> bool:
        """True when a physics step would leave the world as it is: no dynamic body was set by
        hand since the last step, each lies in contact moving slower than ``REST_SPEED``, no
        body moved by hand is within ``REST_CLEARANCE_M`` of one (by PyBullet's bounding boxes),
        and no body was created behind the world's back (through :attr:`client`)."""
        client = self.client
        if self._disturbed or p.getNumBodies(physicsClientId=client) != len(self._bodies):
            return False
        for body_id in self._dynamic:
            linear, angular = p.getBaseVelocity(body_id, physicsClientId=client)
            if max(map(abs, (*linear, *angular))) > REST_SPEED:
                return False
            if not p.getContactPoints(bodyA=body_id, physicsClientId=client):
                return False
            low, high = p.getAABB(body_id, physicsClientId=client)
            near = p.getOverlappingObjects(
                [v - REST_CLEARANCE_M for v in low],
                [v + REST_CLEARANCE_M for v in high],
                physicsClientId=client,
            )
            movers = self._moved.union(self._dynamic).difference((body_id,))
            if any(other in movers for other, _ in near or ()):
                return False
        return True

    def save_state(self) -> int:
        """Snapshot of the whole physics state, for exact resets."""
        return int(p.saveState(physicsClientId=self.client))

    def restore_state(self, state_id: int) -> None:
        """Return to a snapshot from :meth:`save_state`, forgetting the contacts Bullet cached
        since (:meth:`_forget_contacts`; a dynamic body's orientation comes back within a
        rounding, the same one every time)."""
        p.restoreState(stateId=state_id, physicsClientId=self.client)
        self._joints_set.clear()
        self._forget_contacts()
        self._disturbed = True

    def _forget_contacts(self) -> None:
        """Drop the contact points Bullet keeps for each dynamic body between steps.

        ``restoreState`` leaves them: a ball that ended an episode within a couple of
        centimetres of its next start kept a stale carpet contact into the next episode, which
        then crept by about 2e-7 m a step, so the same seed and actions gave different
        observations after different previous episodes. Each dynamic body is lifted clear of
        everything for one collision pass (which releases its contacts) and put back.
        """
        client = self.client
        poses = [p.getBasePositionAndOrientation(b, physicsClientId=client) for b in self._dynamic]
        velocities = [p.getBaseVelocity(b, physicsClientId=client) for b in self._dynamic]
        for k, body_id in enumerate(self._dynamic):
            clear = (0.0, 0.0, CONTACT_CLEAR_HEIGHT_M * (k + 1))
            p.resetBasePositionAndOrientation(body_id, clear, poses[k][1], physicsClientId=client)
        p.performCollisionDetection(physicsClientId=client)
        for body_id, (position, orientation), (linear, angular) in zip(
            self._dynamic, poses, velocities, strict=True
        ):
            p.resetBasePositionAndOrientation(
                body_id, position, orientation, physicsClientId=client
            )
            p.resetBaseVelocity(body_id, linear, angular, physicsClientId=client)

    # ----- sensing ------------------------------------------------------------------------
    def ray_test(
        self, starts: FloatArray, ends: FloatArray, *, transparent_body: int = -1
    ) -> tuple[FloatArray, NDArray[np.int64]]:
        """Batched ray casts: (N, 3) starts and ends -> hit fractions (N,) and body ids (N,).

        A fraction of 1.0 with body id -1 means no hit. The rays pass through
        ``transparent_body`` (-1: none), such as the robot whose sensor casts them: its own
        limbs, swaying about the sensor, must not stop them.
        """
        mask = -1 if transparent_body < 0 else ~self._filter_bit(transparent_body)
        batch = p.MAX_RAY_INTERSECTION_BATCH_SIZE
        hits = []
        for lo in range(0, len(starts), batch):
            hits += p.rayTestBatch(
                starts[lo : lo + batch].tolist(),
                ends[lo : lo + batch].tolist(),
                collisionFilterMask=mask,
                physicsClientId=self.client,
            )
        ids = np.array([hit[0] for hit in hits], dtype=np.int64)
        fractions = np.array([hit[2] for hit in hits], dtype=np.float64)
        fractions[ids < 0] = 1.0
        return fractions, ids

    def _filter_bit(self, body_id: int) -> int:
        """The private collision filter group of ``body_id``, given to it (base and links) on
        first use. The body still collides with what it did: dynamic bodies with everything,
        kinematic ones (robots) with everything but the static scene, as by Bullet's defaults."""
        if body_id not in self._filter_bits:
            if body_id not in self._bodies.values():
                raise ValueError(f"transparent_body must be a body of this world, got {body_id}")
            if len(self._filter_bits) == len(PRIVATE_FILTER_BITS):
                raise RuntimeError(
                    f"at most {len(PRIVATE_FILTER_BITS)} bodies can be transparent to ray tests"
                )
            bit = PRIVATE_FILTER_BITS[len(self._filter_bits)]
            collides_with = -1 if body_id in self._dynamic else ~STATIC_FILTER
            client = self.client
            for link in range(-1, p.getNumJoints(body_id, physicsClientId=client)):
                p.setCollisionFilterGroupMask(
                    body_id, link, bit, collides_with, physicsClientId=client
                )
            self._filter_bits[body_id] = bit
        return self._filter_bits[body_id]

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
        _, _, rgba, depth, seg = _tiny_render(
            self.client, width, height, view, projection, lighting
        )
        rgb = np.ascontiguousarray(
            np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3]
        )
        labels = np.asarray(seg, dtype=np.int32).reshape(height, width)
        if self._floor is not None:
            # where nothing was drawn, and where the floor lies in front of what was: as the
            # renderer's depth test would have it (objects meet the floor at z = 0)
            drawn = np.asarray(depth, dtype=np.float32).reshape(height, width)
            paint = _floor_depth(self._floor, width, height, view, projection) < drawn
            rgb[paint] = self._floor_colour(lighting)
            labels[paint] = self._floor.body
        return rgb, labels

    def _floor_colour(self, lighting: Lighting) -> NDArray[np.uint8]:
        """The RGB (3,) the tiny renderer shades the painted floor in under ``lighting``: the
        middle pixel of a 3 x 3 render of the floor alone, looking straight down at it (kept
        for the last lighting asked for: an episode's frames share one)."""
        if self._floor_colour_for is None or self._floor_colour_for[0] != lighting:
            assert self._floor is not None  # render() asks only for a painted floor
            if self._probe is None:
                self._probe = _floor_probe(self._floor.rgba)
                self._connected.append(self._probe)
            _, _, rgba, _, _ = _tiny_render(
                self._probe,
                3,
                3,
                p.computeViewMatrix([0, 0, 1], [0, 0, 0], [0, 1, 0]),
                p.computeProjectionMatrixFOV(90.0, 1.0, 0.1, 10.0),
                lighting,
            )
            colour = np.asarray(rgba, dtype=np.uint8).reshape(3, 3, 4)[1, 1, :3].copy()
            self._floor_colour_for = (lighting, colour)
        return self._floor_colour_for[1]

    def close(self) -> None:
        """Disconnect; safe to call more than once."""
        self._disconnect()
        self._client = self._probe = None


# PyBullet's createVisualShape keeps a reference to the lists of a mesh it is given and never
# lets go, so every env that built its scene afresh would leak its meshes' lists (about 1 MB
# an env). An equal mesh is handed the same lists again instead, made once per process.
_MESH_LISTS: dict[bytes, dict[str, list[Any]]] = {}
_MESH_LISTS_KEPT = 256  # distinct meshes kept (a scene has a few dozen)


def _mesh_lists(mesh: TriangleMesh) -> dict[str, list[Any]]:
    """``createVisualShape``'s ``vertices``, ``indices``, ``normals`` (and ``uvs``) of ``mesh``,
    the same list objects for every equal mesh."""
    arrays = {"vertices": mesh.vertices, "indices": mesh.triangles.ravel(), "normals": mesh.normals}
    if mesh.uvs is not None:
        arrays["uvs"] = mesh.uvs
    digest = hashlib.blake2b(digest_size=16)
    for name, array in arrays.items():
        digest.update(f"{name}{array.dtype}{array.shape}".encode())
        digest.update(np.ascontiguousarray(array).tobytes())
    key = digest.digest()
    if key not in _MESH_LISTS:
        if len(_MESH_LISTS) >= _MESH_LISTS_KEPT:
            _MESH_LISTS.clear()
        _MESH_LISTS[key] = {name: array.tolist() for name, array in arrays.items()}
    return _MESH_LISTS[key]


def _disconnect_all(clients: list[int]) -> None:
    """Disconnect the PyBullet ``clients`` (ids) still connected, and forget them."""
    for client in clients:
        if p.isConnected(physicsClientId=client):
            p.disconnect(physicsClientId=client)
    clients.clear()


def _floor_probe(rgba: Sequence[float]) -> int:
    """A new client holding only a 40 m square of colour ``rgba`` at z = 0, facing up."""
    client = p.connect(p.DIRECT)
    half = 20.0
    vis = p.createVisualShape(
        p.GEOM_MESH,
        vertices=[[-half, -half, 0.0], [half, -half, 0.0], [half, half, 0.0], [-half, half, 0.0]],
        indices=[0, 1, 2, 0, 2, 3],
        normals=[[0.0, 0.0, 1.0]] * 4,
        rgbaColor=list(rgba),
        physicsClientId=client,
    )
    p.createMultiBody(baseMass=0.0, baseVisualShapeIndex=vis, physicsClientId=client)
    return client


def _floor_depth(
    floor: PaintedFloor,
    width: int,
    height: int,
    view: Sequence[float],
    projection: Sequence[float],
) -> NDArray[np.float32]:
    """The depth-buffer value of ``floor`` at each pixel of a ``width`` x ``height`` frame,
    (H, W), as ``getCameraImage`` returns depth (0 at the near plane, 1 at the far plane, the
    cleared value); 1 where the pixel's ray does not meet the floor between the planes.

    The tiny renderer samples pixel ``(col, row)`` at viewport point ``(col, height - 1 -
    row)`` (no half-pixel offset). Each pixel's ray runs from the eye through its point on the
    far plane of the column-major OpenGL ``view`` and perspective ``projection`` matrices (16,).
    """
    to_view = np.reshape(view, (4, 4)).T
    to_clip = np.reshape(projection, (4, 4)).T
    near = to_clip[2, 3] / (to_clip[2, 2] - 1.0)
    far = to_clip[2, 3] / (to_clip[2, 2] + 1.0)
    c = np.linalg.inv(to_clip @ to_view)  # world from clip
    eye = np.linalg.inv(to_view)[:3, 3]
    x = 2.0 * np.arange(width) / width - 1.0
    y = 2.0 * (height - 1 - np.arange(height)) / height - 1.0
    # a pixel's far-plane point is (d_x, d_y, d_z, w) / w with each of d and w linear in its
    # device coordinates (x, y); d = its homogeneous point less w times the eye: d / w is the
    # ray from the eye to it. Grids (H, W) in float32: plenty for metres and pixels.
    w_row, d_row = c[3, 0] * x, [c[k, 0] * x - eye[k] * c[3, 0] * x for k in range(3)]
    w_col = c[3, 1] * y + c[3, 2] + c[3, 3]
    d_col = [c[k, 1] * y + c[k, 2] + c[k, 3] - eye[k] * w_col for k in range(3)]
    # only rows with a descending ray (d_z / w < 0 at either end: both are linear along a row)
    ends = [(d_col[2] + d_row[2][j]) / (w_col + w_row[j]) for j in (0, -1)]
    rows = np.flatnonzero((ends[0] < 0) | (ends[1] < 0))
    w = _outer_sum(w_col[rows], w_row)
    d = [_outer_sum(col[rows], row) for col, row in zip(d_col, d_row, strict=True)]
    # a ray parallel to the floor (d_z = 0 on a row that descends at one end) never meets it:
    # its r is infinite (or NaN), which every test below refuses
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.float32(-eye[2]) / d[2]  # the ray meets z = 0 at eye + r * d
        s = r * w  # ... this far along the ray to the far plane (eye depth s * far)
        hx, hy = floor.half_extents
        seen = (
            (s >= near / far)
            & (s <= 1.0)
            & (np.abs(eye[0] + r * d[0]) <= hx)
            & (np.abs(eye[1] + r * d[1]) <= hy)
        )
    depth = np.ones((height, width), dtype=np.float32)
    floor_depth = (far - near / np.where(seen, s, 1.0)) / (far - near)  # as pybullet's buffer
    depth[rows] = np.where(seen, floor_depth, 1.0)
    return depth


def _outer_sum(column: FloatArray, row: FloatArray) -> NDArray[np.float32]:
    """The grid (H, W) ``column[:, None] + row[None, :]`` in float32."""
    return np.add.outer(column.astype(np.float32), row.astype(np.float32))


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


def _tiny_render(
    client: int,
    width: int,
    height: int,
    view: Sequence[float],
    projection: Sequence[float],
    lighting: Lighting,
) -> Any:
    """PyBullet's tiny renderer, without shadows, under ``lighting``: ``getCameraImage``'s
    (width, height, rgba, depth, segmentation)."""
    return p.getCameraImage(
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
        physicsClientId=client,
    )
