"""The PyBullet world, scene and robot against known geometry and the Nao's limits."""

from __future__ import annotations

import functools
import gc
import math
from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest

from perception.geometry import project_points
from spl_env.robots.nao import NaoCommand, NaoRobot, RobotConfig
from spl_env.scenes.spl_field import (
    POSTER_SETS,
    SceneBodies,
    SceneConfig,
    SplFieldScene,
    build_scene,
)
from spl_env.sensors.camera import Camera, CameraConfig, EpisodeLighting
from spl_env.sensors.sonar import Sonar, SonarConfig
from spl_env.sim.world import (
    MAX_PARTS_PER_BODY,
    PRIVATE_FILTER_BITS,
    BulletWorld,
    TriangleMesh,
    VisualPart,
    _mesh_lists,
)

SCENE = SceneConfig()


@pytest.fixture(scope="module")
def scene() -> Iterator[tuple[BulletWorld, SceneBodies, NaoRobot]]:
    world = BulletWorld(time_step_s=0.01)
    bodies = build_scene(world, SCENE, np.random.default_rng(0))
    robot = NaoRobot(world, "self", team=0, config=RobotConfig())
    yield world, bodies, robot
    world.close()


def test_camera_projection_matches_rendered_labels(scene) -> None:
    world, bodies, robot = scene
    poles = SCENE.poles.positions(SCENE.dimensions)
    geometry = SCENE.poles.geometry
    robot.place(np.array([-1.0, 0.5, math.pi / 2]), head=np.array([0.3, 0.1]))
    camera = Camera(CameraConfig(noise_std=0.0))
    position, rotation = robot.camera_pose_world()
    _, labels = camera.render(
        world, position, rotation, EpisodeLighting.default(), np.random.default_rng(0)
    )
    m = camera.config.model
    mask = labels == world.body(bodies.poles[0])
    rows, cols = np.nonzero(mask)
    assert mask.sum() > 100, "pole 0 should be in view"
    # the silhouette's bottom and top come from the rim nearest the camera
    towards = (poles[0] - position[:2]) / np.linalg.norm(poles[0] - position[:2])
    rim = poles[0] - geometry.radius_m * towards
    ends = np.array([[*rim, 0.0], [*rim, geometry.top_m]])
    uv, front = project_points((ends - position) @ rotation, m.fx, m.fy, m.cx, m.cy)
    assert front.all()
    # columns: pixel i is centred at u = i (tight below). Rows: the tiny renderer's rows sit up to
    # one pixel higher than the pinhole model puts them (measured 0.8-1.0 px), so the label's
    # outer edges meet the projected base and top within one pixel
    assert uv[0, 1] == pytest.approx(rows.max() + 0.5, abs=1.1)
    assert uv[1, 1] == pytest.approx(rows.min() - 0.5, abs=1.1)
    # one row through the middle: centred on the projected axis, 2 r f / depth wide
    middle = np.array([*poles[0], geometry.top_m / 2])
    [(u_mid, v_mid)], _ = project_points(
        ((middle - position) @ rotation)[None, :], m.fx, m.fy, m.cx, m.cy
    )
    depth = float((middle - position) @ rotation[:, 0])
    row_cols = cols[rows == round(v_mid)]
    assert (row_cols.min() + row_cols.max()) / 2 == pytest.approx(u_mid, abs=0.6)
    assert row_cols.max() + 1 - row_cols.min() == pytest.approx(
        2 * geometry.radius_m * m.fx / depth, abs=1.0
    )


def test_ray_test_hits_pole_at_its_surface(scene) -> None:
    world, bodies, _ = scene
    pole = SCENE.poles.positions(SCENE.dimensions)[1]
    start = np.array([[pole[0], pole[1] - 2.0, 0.3]])
    end = np.array([[pole[0], pole[1] + 2.0, 0.3]])
    fractions, ids = world.ray_test(start, end)
    assert ids[0] == world.body(bodies.poles[1])
    assert 4.0 * fractions[0] == pytest.approx(2.0 - SCENE.poles.geometry.radius_m, abs=1e-3)


def test_walk_respects_speed_and_acceleration_limits(scene) -> None:
    _, _, robot = scene
    cfg = robot.config
    robot.place(np.zeros(3))
    first = robot.walk_step(np.array([1.0, 0.0, 0.0]), 0.1)
    assert first[0] == pytest.approx(cfg.max_accel[0] * 0.1 * 0.1)  # v after one step times dt
    for _ in range(50):
        robot.walk_step(np.array([1.0, -1.0, 5.0]), 0.1)
    np.testing.assert_allclose(
        robot.velocity, [cfg.max_speed[0], -cfg.max_speed[1], cfg.max_speed[2]]
    )


def test_walk_increment_is_exact_constant_twist_arc(scene) -> None:
    _, _, robot = scene
    robot.place(np.zeros(3))
    robot.velocity = np.array([0.2, 0.0, 0.5])
    inc = robot.walk_step(np.array([0.2, 0.0, 0.5]), 0.1)
    # a circle of radius v / omega turned through omega * dt
    r, a = 0.2 / 0.5, 0.05
    np.testing.assert_allclose(inc, [r * math.sin(a), r * (1 - math.cos(a)), a], atol=1e-12)


def test_head_limits_and_speed(scene) -> None:
    _, _, robot = scene
    cfg = robot.config
    robot.place(np.zeros(3))
    robot.move_head(np.array([3.0, 3.0]), 0.1)
    np.testing.assert_allclose(robot.head, [cfg.head_speed_rps * 0.1] * 2)
    for _ in range(30):
        robot.move_head(np.array([3.0, 3.0]), 0.1)
    np.testing.assert_allclose(robot.head, [cfg.head_yaw_limit_rad, cfg.head_pitch_max_rad])
    assert math.degrees(cfg.head_yaw_limit_rad) == pytest.approx(119.5)


def test_standing_top_camera_height(scene) -> None:
    _, _, robot = scene
    robot.place(np.zeros(3))
    position, rotation = robot.camera_pose_world()
    assert position[2] == pytest.approx(0.52, abs=0.01)  # ARCHITECTURE §7: about 0.52 m
    assert rotation[:, 0][2] == pytest.approx(-math.sin(robot.config.camera_tilt_rad))


def test_too_many_parts_rejected() -> None:
    world = BulletWorld(time_step_s=0.01)
    part = VisualPart(shape="box", size=(0.1, 0.1, 0.1), position=(0, 0, 0), rgba=(1, 1, 1, 1))
    with pytest.raises(ValueError, match="parts"):
        world.add_static("many", [part] * (MAX_PARTS_PER_BODY + 1))
    world.close()
    world.close()  # twice is fine
    with pytest.raises(RuntimeError, match="closed"):
        _ = world.client


def test_bad_configs_rejected() -> None:
    with pytest.raises(ValueError, match="max_speed"):
        RobotConfig(max_speed=(0.2, 0.1))
    with pytest.raises(ValueError, match="board_height_m"):
        SceneConfig(board_height_m=-1.0)
    with pytest.raises(ValueError, match="time_step_s"):
        BulletWorld(time_step_s=0.0)
    world = BulletWorld(time_step_s=0.01)
    with pytest.raises(ValueError, match="team must be 0 or 1"):
        NaoRobot(world, "r", team=2, config=RobotConfig())
    with pytest.raises(TypeError, match="team_colours must be a bool"):
        NaoRobot(world, "r", team=0, config=RobotConfig(), team_colours=1)  # type: ignore[arg-type]
    world.close()


def test_camera_pose_matches_pybullet_head_link_while_swaying(scene) -> None:
    import pybullet as p

    from perception.geometry import rot_y

    world, _, robot = scene
    robot.place(np.array([0.4, -0.7, 2.9]), head=np.array([0.6, -0.3]))
    for _ in range(7):  # walk a little so the gait sways the body
        robot.walk_step(np.array([0.2, 0.05, 0.3]), 0.1)
    robot.sync()
    assert abs(robot.sway()[0]) > 1e-3
    link = p.getLinkState(
        world.body("self"), 1, computeForwardKinematics=True, physicsClientId=world.client
    )
    link_pos = np.array(link[4])
    link_rot = np.array(p.getMatrixFromQuaternion(link[5])).reshape(3, 3)
    position, rotation = robot.camera_pose_world()
    np.testing.assert_allclose(
        position, link_pos + link_rot @ robot.config.camera_offset_m, atol=1e-6
    )
    np.testing.assert_allclose(rotation, link_rot @ rot_y(robot.config.camera_tilt_rad), atol=1e-6)


def test_field_scene_answers_what_is_where() -> None:
    world = BulletWorld(time_step_s=0.01)
    scene = SplFieldScene(world, SCENE)
    codes = SCENE.poles.codes()
    assert scene.codes == codes and scene.dimensions == SCENE.dimensions
    np.testing.assert_array_equal(scene.landmark_ids, [c.landmark_id for c in codes])
    positions = SCENE.poles.positions(SCENE.dimensions)
    np.testing.assert_array_equal(scene.landmarks, positions[scene.landmark_ids])
    # the pole bodies in landmark order stand where the landmarks are
    for landmark_id, body_id, xy in zip(
        scene.landmark_ids, scene.pole_body_ids(), scene.landmarks, strict=True
    ):
        assert body_id == world.body(scene.bodies.poles[int(landmark_id)])
        np.testing.assert_allclose(world.position(scene.bodies.poles[int(landmark_id)])[:2], xy)
    scene.place_ball(np.array([1.0, -0.5]), np.array([0.3, 0.2]))
    ball, velocity = scene.ball_state()
    np.testing.assert_allclose(ball, [1.0, -0.5], atol=1e-9)
    np.testing.assert_allclose(velocity, [0.3, 0.2], atol=1e-9)
    scene.place_ball(np.array([-2.0, 1.0]))  # placed without a velocity: at rest
    ball, velocity = scene.ball_state()
    np.testing.assert_allclose(ball, [-2.0, 1.0], atol=1e-9)
    np.testing.assert_allclose(velocity, [0.0, 0.0], atol=1e-12)
    world.close()


def test_field_scene_draws_posters_from_the_scene_seed_or_a_given_generator(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    def posters(config: SceneConfig, poster_rng: np.random.Generator | None = None) -> list[str]:
        """The poster files the scene paints on its boards, in order."""
        world = BulletWorld(time_step_s=0.01)
        painted: list[str] = []
        paint = world.set_texture

        def record(name: str, path: str) -> None:
            painted.append(path.rsplit("/", 1)[-1])
            paint(name, path)

        monkeypatch.setattr(world, "set_texture", record)
        SplFieldScene(world, config, poster_rng=poster_rng)
        world.close()
        return painted

    seeded = posters(SceneConfig(scene_seed=7))
    assert len(seeded) > 10 and len(set(seeded)) > 1
    assert posters(SceneConfig(scene_seed=7)) == seeded
    assert posters(SceneConfig(scene_seed=8)) != seeded
    # a generator passed in draws the posters instead of scene_seed, and is advanced by them
    rng = np.random.default_rng(7)
    assert posters(SceneConfig(scene_seed=3), poster_rng=rng) == seeded
    reference = np.random.default_rng(7)
    for _ in seeded:  # one draw per panel
        reference.integers(len(POSTER_SETS["classic"]))
    assert rng.integers(1 << 30) == reference.integers(1 << 30)


def test_the_scene_names_each_panels_poster_from_the_set_asked_for() -> None:
    for poster_set, files in POSTER_SETS.items():
        world = BulletWorld(time_step_s=0.01)
        scene = SplFieldScene(world, SceneConfig(scene_seed=5, poster_set=poster_set))
        painted = scene.bodies.posters
        assert len(painted) > 10 and set(painted.values()) <= set(files)
        assert all(world.body(name) >= 0 for name in painted)
        if poster_set == "textured":  # every panel its own poster: the two ends differ
            assert len(set(painted.values())) == len(painted)
        world.close()
    with pytest.raises(ValueError, match="poster_set"):
        SceneConfig(poster_set="plain")


def test_camera_pose_follows_every_part_of_the_robot_state(scene) -> None:
    """The memoised camera poses change with the pose, head, walk velocity, gait phase and
    config, even without a sync: each equals a fresh robot's in the same state."""
    world, _, robot = scene
    probe = NaoRobot(world, "probe", team=1, config=RobotConfig())

    def same_as_fresh() -> None:
        probe.config, probe.pose, probe.head = robot.config, robot.pose, robot.head
        probe.velocity, probe.gait_phase = robot.velocity, robot.gait_phase
        probe._camera_pose_memo.clear()
        probe._camera_state_memo = None
        for camera in ("top", "bottom"):
            for got, want in zip(
                robot.camera_pose_world(camera), probe.camera_pose_world(camera), strict=True
            ):
                np.testing.assert_array_equal(got, want)
        np.testing.assert_array_equal(robot.camera_state().position, probe.camera_state().position)

    robot.place(np.array([0.5, -0.3, 0.2]), head=np.array([0.1, 0.2]))
    same_as_fresh()
    first = robot.camera_pose_world()[0]
    robot.pose = np.array([1.0, -0.3, 0.2])
    same_as_fresh()
    assert not np.allclose(robot.camera_pose_world()[0], first)
    robot.head = np.array([-0.4, 0.1])
    same_as_fresh()
    robot.velocity, robot.gait_phase = np.array([0.2, 0.0, 0.0]), 1.0
    same_as_fresh()
    before = robot.camera_pose_world()[0]
    robot.config = RobotConfig(camera_offset_m=(0.2, 0.0, 0.1))
    same_as_fresh()
    assert not np.allclose(robot.camera_pose_world()[0], before)
    with pytest.raises(ValueError):  # the shared camera state is read-only
        robot.camera_state().position[0] = 0.0
    robot.config = RobotConfig()
    robot.place(np.zeros(3))


def test_a_walking_nao_hears_a_wall_ahead_in_every_frame() -> None:
    """A wall 0.9 m in front of the sonar, no dropout: every sector hears it in every frame,
    standing and swaying through the gait. The sonar's rays start inside the legs' boxes, so
    they must pass through our own body: without that, Bullet stopped some at distance 0 and the
    sonar missed the wall in 9 of these 100 frames."""
    world = BulletWorld(time_step_s=0.01)
    robot = NaoRobot(world, "self", team=0, config=RobotConfig())
    grey = (0.5, 0.5, 0.5, 1.0)
    wall = VisualPart(shape="box", size=(0.05, 2.0, 0.5), position=(1.0, 0.0, 0.5), rgba=grey)
    world.add_static("wall", [wall])
    sonar = Sonar(SonarConfig(dropout_probability=0.0))
    rng = np.random.default_rng(0)
    rays = functools.partial(world.ray_test, transparent_body=world.body("self"))
    robot.place(np.zeros(3))
    deaf_standing = np.isnan(sonar.measure(rays, robot.pose, rng))
    assert not deaf_standing[:, 0].any()
    robot.velocity = np.array([0.25, 0.0, 0.0])  # full speed ahead: the most sway
    deaf_frames = 0
    for k in range(100):
        robot.gait_phase = (0.37 * k) % (2 * math.pi)
        robot.sync()
        echoes = sonar.measure(rays, robot.pose, rng)
        deaf_frames += bool(np.isnan(echoes[:, 0]).any())
    world.close()
    assert deaf_frames == 0


def test_rays_pass_through_the_transparent_body_alone_and_it_still_collides() -> None:
    """A ray along the x axis through a robot to a wall: it stops on the robot unless the robot
    is transparent to it, after a restored snapshot too; other rays still stop on the robot;
    and a ball rolled at the transparent robot still bounces off it, while a transparent ball
    still lies on the floor."""
    world = BulletWorld(time_step_s=0.01)
    robot = NaoRobot(world, "self", team=0, config=RobotConfig())
    robot.place(np.zeros(3))
    grey = (0.5, 0.5, 0.5, 1.0)
    wall = VisualPart(shape="box", size=(0.05, 2.0, 0.5), position=(1.0, 0.0, 0.5), rgba=grey)
    world.add_static("wall", [wall])
    floor = VisualPart(shape="box", size=(4.0, 4.0, 0.05), position=(0.0, 0.0, -0.05), rgba=grey)
    world.add_static("floor", [floor])
    start, end = np.array([[-0.5, 0.0, 0.3]]), np.array([[1.5, 0.0, 0.3]])
    self_id, wall_id = world.body("self"), world.body("wall")
    before_anything = world.save_state()  # an env's episode start, restored at each reset
    _, opaque = world.ray_test(start, end)
    fraction, through = world.ray_test(start, end, transparent_body=self_id)
    _, still_opaque = world.ray_test(start, end)
    assert opaque[0] == self_id and still_opaque[0] == self_id
    assert through[0] == wall_id
    world.restore_state(before_anything)
    assert world.ray_test(start, end, transparent_body=self_id)[1][0] == wall_id
    assert 2.0 * fraction[0] == pytest.approx(1.5 - 0.05, abs=1e-6)  # the wall's near face
    with pytest.raises(ValueError, match="transparent_body"):
        world.ray_test(start, end, transparent_body=999)

    radius = 0.05
    ball = world.add_sphere(
        "ball",
        radius_m=radius,
        mass_kg=0.05,
        position=(-0.6, 0.0, radius),
        rgba=grey,
        rolling_friction=0.0,
        restitution=0.5,
    )
    world.ray_test(start, end, transparent_body=ball)
    world.set_velocity("ball", linear=(1.5, 0.0, 0.0))
    for _ in range(100):
        world.step(1)
    x, _, z = world.position("ball")
    assert x < -0.05  # stopped by the robot's legs, which reach about 0.05 m behind its origin
    assert z == pytest.approx(radius, abs=2e-3)  # on the floor, not through it
    world.close()


def test_at_most_the_private_filter_bits_worth_of_bodies_become_transparent() -> None:
    """Each transparent body takes one of Bullet's 29 free collision filter bits; the 30th is
    refused with a clear error rather than sharing a bit (which would hide one from the
    other's rays)."""
    world = BulletWorld(time_step_s=0.01)
    grey = (0.5, 0.5, 0.5, 1.0)
    start, end = np.zeros((1, 3)), np.ones((1, 3))
    for k in range(len(PRIVATE_FILTER_BITS) + 1):
        part = VisualPart(shape="box", size=(0.1, 0.1, 0.1), position=(k, 5.0, 0.1), rgba=grey)
        body = world.add_static(f"box{k}", [part])
        if k < len(PRIVATE_FILTER_BITS):
            world.ray_test(start, end, transparent_body=body)
    with pytest.raises(RuntimeError, match="at most 29 bodies"):
        world.ray_test(start, end, transparent_body=body)
    world.close()


def test_set_joints_holds_after_a_restored_snapshot_and_a_physics_step() -> None:
    """set_joints leaves joints alone that it set to the same angles before, unless a snapshot
    or a physics step may have moved them since: after either, the angles asked for hold."""
    import pybullet as p

    world = BulletWorld(time_step_s=0.01)
    NaoRobot(world, "self", team=0, config=RobotConfig())
    world.add_sphere(
        "ball",
        radius_m=0.05,
        mass_kg=0.05,
        position=(2.0, 0.0, 1.0),
        rgba=(1, 1, 1, 1),
        rolling_friction=0.0,
        restitution=0.0,
    )
    body = world.body("self")

    def head() -> list[float]:
        return [s[0] for s in p.getJointStates(body, [0, 1], physicsClientId=world.client)]

    try:
        world.set_joints("self", [0.0, 0.0])
        snapshot = world.save_state()
        world.set_joints("self", [0.5, -0.2])
        world.restore_state(snapshot)  # the joints are back at 0, 0
        assert head() == [0.0, 0.0]
        world.set_joints("self", [0.5, -0.2])
        assert head() == pytest.approx([0.5, -0.2], abs=1e-12)
        # a physics step may move joints (here done by hand, as a step could)
        p.resetJointStatesMultiDof(body, [0, 1], [[0.0], [0.0]], physicsClientId=world.client)
        world.set_pose("ball", (0.0, 0.0, 1.0), 0.0)  # a dropped ball: the world steps
        assert not world.at_rest()
        world.step(1)
        world.set_joints("self", [0.5, -0.2])
        assert head() == pytest.approx([0.5, -0.2], abs=1e-12)
    finally:
        world.close()


def _next_client_id() -> int:
    """The id PyBullet gives the next client (it reuses the lowest free one)."""
    world = BulletWorld(time_step_s=0.01)
    client = world.client
    world.close()
    return client


def test_a_world_dropped_unclosed_or_an_env_refused_while_building_frees_its_client() -> None:
    """A refused ``gym.make`` gives no env to close: the world it had connected is closed with
    the refusal; a world dropped without ``close()`` disconnects when it is collected."""
    free = _next_client_id()
    with pytest.raises(ValueError, match="shot_distance_m"):
        gym.make("SPL/Goalie-v0", **{"task.shot_distance_m": (30.0, 40.0)})
    gc.collect()
    assert _next_client_id() == free
    world = BulletWorld(time_step_s=0.01)
    assert world.client == free
    del world
    gc.collect()
    assert _next_client_id() == free
    world = BulletWorld(time_step_s=0.01)
    world.close()
    world.close()  # twice is fine
    assert _next_client_id() == free


def test_equal_meshes_hand_pybullet_the_same_lists() -> None:
    """PyBullet keeps the lists a mesh is given: an env rebuilding its scene hands over the
    lists of an equal mesh made before (no new memory), with the mesh's values."""
    corners = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    up = np.tile([0.0, 0.0, 1.0], (4, 1))

    def quad(z: float) -> TriangleMesh:
        return TriangleMesh(
            vertices=corners + np.array([0.0, 0.0, z]),
            triangles=np.array([[0, 1, 2], [0, 2, 3]]),
            normals=up,
        )

    first, again, other = _mesh_lists(quad(0.0)), _mesh_lists(quad(0.0)), _mesh_lists(quad(0.5))
    assert all(first[name] is again[name] for name in first)
    assert first["vertices"] == corners.tolist() and first["indices"] == [0, 1, 2, 0, 2, 3]
    assert first["normals"] == up.tolist() and "uvs" not in first
    assert other["vertices"] != first["vertices"]


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"walk": np.array([math.nan, 0.0, 0.0])}, "NaoCommand.walk"),
        ({"walk": np.zeros(2)}, "NaoCommand.walk"),
        ({"head": np.array([0.0, math.inf])}, "NaoCommand.head"),
    ],
)
def test_a_nao_command_that_is_not_finite_is_refused(kwargs: dict, name: str) -> None:
    """A NaN walk would stay in the walk engine's velocity for good, whatever came after."""
    with pytest.raises(ValueError, match=name):
        NaoCommand(**kwargs)
