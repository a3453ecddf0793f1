"""The geometric camera mode against the renderer and the colour filter on the same views."""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import spl_env  # noqa: F401  (registers the env ids)
from perception.metrics import landmark_range_bearing
from perception.representations import POLE_SIGHTINGS
from perception.vision import ColourFilterConfig, ColourPoleDetector
from spl_env.envs.active_vision import ActiveVisionEnv
from spl_env.sensors.camera import EpisodeLighting
from spl_env.sensors.emulation.poles import (
    GeometricCameraConfig,
    GeometricPoleCamera,
    GeometricPoleSightings,
)

GEOMETRIC = {"camera_mode": "geometric", "frontend": "colour", "episode_s": 3.0}


@pytest.fixture(scope="module")
def env() -> Iterator[ActiveVisionEnv]:
    env = ActiveVisionEnv(n_other_robots=1, **GEOMETRIC)
    env.reset(seed=0)
    yield env
    env.close()


def _emulator(env: ActiveVisionEnv) -> GeometricPoleSightings:
    emulator = env.rig.emulators[POLE_SIGHTINGS]
    assert isinstance(emulator, GeometricPoleSightings)
    return emulator


def _camera(env: ActiveVisionEnv) -> GeometricPoleCamera:
    return _emulator(env).camera


def _look(env: ActiveVisionEnv, pose: tuple[float, float, float], head_yaw: float = 0.0) -> None:
    env.robots[0].place(np.array(pose), head=np.array([head_yaw, 0.0]))


def _detector(env: ActiveVisionEnv) -> ColourPoleDetector:
    scene = env.config.scene
    return ColourPoleDetector(
        ColourFilterConfig(), env.config.sensors.camera.model, env.scene.codes, scene.poles.geometry
    )


def test_band_centres_agree_with_rendered_detection(env: ActiveVisionEnv) -> None:
    env.robots[1].place(np.array([4.0, -2.5, 0.0]))  # out of the way
    robot, camera = env.robots[0], _camera(env)
    detector = _detector(env)
    pole = env.scene.landmarks[1]  # id 1 at (0, 3.35)
    assert env.scene.landmark_ids[1] == 1
    for distance in (1.5, 2.5, 3.5):
        _look(env, (pole[0], pole[1] - distance, math.pi / 2))
        position, rotation = robot.camera_pose_world()
        seen = {b.landmark_id: b for b in camera.visible(env.world, position, rotation)}
        image, _ = env.rig.camera.render(
            env.world, position, rotation, EpisodeLighting.default(), np.random.default_rng(0)
        )
        found = {o.landmark_id: o for o in detector.detect(image, robot.camera_state())}
        assert 1 in seen and 1 in found
        # the detector's reported pixel is the midpoint of its two band centres
        midpoint = (seen[1].upper + seen[1].lower) / 2
        np.testing.assert_allclose(found[1].pixel, midpoint, atol=1.5)
        # and through the shared measurement model the ideal centres give the placed distance
        obs = detector.observe_band_centres(
            1, seen[1].upper, seen[1].lower, seen[1].box, robot.camera_state()
        )
        assert obs is not None
        true_range = float(np.hypot(*(pole - robot.pose[:2])))
        assert obs.range_m == pytest.approx(true_range, rel=0.01)


def test_occluded_and_out_of_view_poles_are_not_seen(env: ActiveVisionEnv) -> None:
    camera, robot, other = _camera(env), env.robots[0], env.robots[1]
    pole = env.scene.landmarks[1]
    _look(env, (pole[0], pole[1] - 3.0, math.pi / 2))
    other.place(np.array([4.0, -2.5, 0.0]))
    position, rotation = robot.camera_pose_world()
    assert 1 in [b.landmark_id for b in camera.visible(env.world, position, rotation)]
    other.place(np.array([pole[0], pole[1] - 2.4, 0.0]))  # its head blocks the view
    position, rotation = robot.camera_pose_world()
    assert 1 not in [b.landmark_id for b in camera.visible(env.world, position, rotation)]
    other.place(np.array([4.0, -2.5, 0.0]))
    _look(env, (0.0, 0.0, 0.0))  # facing the goal: the nearest poles are 48° off the axis
    position, rotation = robot.camera_pose_world()
    assert camera.visible(env.world, position, rotation) == []


def test_emulated_sightings_are_the_colour_filter_model_of_the_band_centres(
    env: ActiveVisionEnv,
) -> None:
    env.robots[1].place(np.array([4.0, -2.5, 0.0]))
    robot, emulator = env.robots[0], _emulator(env)
    pole = env.scene.landmarks[1]
    _look(env, (pole[0] + 0.3, pole[1] - 2.0, math.pi / 2))
    state = robot.camera_state()
    sightings = emulator.observe(env.world, robot, state, np.random.default_rng(1), 0.0)
    [one] = [s for s in sightings if s.landmark_id == 1]
    # the same draws through the camera, measured by the detector's model
    position, rotation = robot.camera_pose_world()
    [bands] = [
        b
        for b in emulator.camera.observe(env.world, position, rotation, np.random.default_rng(1))
        if b.landmark_id == 1
    ]
    expected = emulator.detector.observe_band_centres(1, bands.upper, bands.lower, bands.box, state)
    assert expected is not None
    assert (one.range_m, one.bearing_rad) == (expected.range_m, expected.bearing_rad)
    true_range, true_bearing = landmark_range_bearing(
        robot.pose, env.scene.landmark_ids, env.scene.landmarks
    )[1]
    assert one.range_m == pytest.approx(true_range, rel=0.05)
    assert one.bearing_rad == pytest.approx(true_bearing, abs=0.02)
    ids = [s.landmark_id for s in sightings]
    assert ids == sorted(set(ids))  # at most one per pole, in id order


def test_recall_is_piecewise_by_smear() -> None:
    config = GeometricCameraConfig(recall_by_smear=((0.5, 1.0), (2.0, 0.5)))
    np.testing.assert_array_equal(
        config.recall(np.array([0.0, 0.49, 0.5, 1.9, 2.0, 9.0])), [1.0, 1.0, 0.5, 0.5, 0.0, 0.0]
    )
    with pytest.raises(ValueError, match="recall_by_smear"):
        GeometricCameraConfig(recall_by_smear=((3.0, 1.0), (2.0, 0.5)))
    with pytest.raises(ValueError, match="recall_by_smear"):
        GeometricCameraConfig(recall_by_smear=((float("nan"), 1.0),))
    with pytest.raises(ValueError, match="pixel_std_u_px"):
        GeometricCameraConfig(pixel_std_u_px=-1.0)


def test_observe_thins_and_disturbs_with_the_configured_statistics(env: ActiveVisionEnv) -> None:
    from scipy import stats

    env.robots[1].place(np.array([4.0, -2.5, 0.0]))
    pole = env.scene.landmarks[1]
    _look(env, (pole[0], pole[1] - 2.0, math.pi / 2))
    position, rotation = env.robots[0].camera_pose_world()
    camera = _camera(env)
    [truth] = [b for b in camera.visible(env.world, position, rotation) if b.landmark_id == 1]
    config = GeometricCameraConfig(
        recall_by_smear=((1.0, 0.5),), pixel_std_u_px=0.8, pixel_std_v_px=0.3
    )
    noisy = type(camera)(
        config,
        camera.model,
        camera.pole,
        camera.positions,
        camera.ids,
        tuple(int(b) for b in camera.body_ids),
    )
    rng = np.random.default_rng(4)
    n = 2000
    kept = [
        b
        for _ in range(n)
        for b in noisy.observe(env.world, position, rotation, rng)
        if b.landmark_id == 1
    ]
    assert stats.binomtest(len(kept), n, 0.5).pvalue > 0.001
    offsets = np.array(
        [np.concatenate([b.upper - truth.upper, b.lower - truth.lower]) for b in kept]
    )
    for column, std in ((0, 0.8), (1, 0.3), (2, 0.8), (3, 0.3)):
        dof = len(offsets)
        low, high = stats.chi2.ppf([0.0005, 0.9995], dof) / dof
        assert low < np.mean(offsets[:, column] ** 2) / std**2 < high
    # blur of twice the pole's width: nothing is kept
    wide = 2.0 * (truth.box[2] - truth.box[0])
    assert noisy.observe(env.world, position, rotation, rng, blur_px=wide) == ()


def test_geometric_env_passes_checker_and_is_deterministic() -> None:
    env = gym.make(
        "SPL/ActiveVision-v0",
        camera_mode="geometric",
        frontend="colour",
        episode_s=3.0,
        render_mode="rgb_array",
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped, skip_render_check=False)
    assert [str(w.message) for w in caught] == []
    a = np.array([0.3, 0.0], dtype=np.float32)
    env.reset(seed=9)
    first = [env.step(a)[0] for _ in range(10)]
    env.reset(seed=9)
    second = [env.step(a)[0] for _ in range(10)]
    for f, s in zip(first, second, strict=True):
        for key in f:
            np.testing.assert_array_equal(f[key], s[key])
    assert env.render().ndim == 3
    # it does detect: ranges of the poles it reports agree with the truth within 5 %
    env.reset(seed=2)
    checked = 0
    for _ in range(30):
        *_, info = env.step(np.zeros(2, dtype=np.float32))
        core = env.unwrapped
        frame = core.sensor_frame
        # nothing is rendered: the emulator's sightings are what perception reports
        assert frame.image is None
        assert core.perception_output[POLE_SIGHTINGS] is frame.emulated[POLE_SIGHTINGS]
        gt, per = info["ground_truth"], info["perception"]
        truth = landmark_range_bearing(gt["robot_pose"], gt["landmark_ids"], gt["landmarks"])
        ids = [int(i) for i in per["landmark_ids"][per["sighted"]]]
        assert ids == [s.landmark_id for s in frame.emulated[POLE_SIGHTINGS]]
        assert np.all(per["sightings"][~per["sighted"]] == 0.0)
        for landmark_id, (range_m, _) in zip(ids, per["sightings"][per["sighted"]], strict=True):
            assert range_m == pytest.approx(truth[landmark_id][0], rel=0.05)
            checked += 1
    assert checked > 0
    env.close()
    with pytest.raises(ValueError, match="camera_mode"):
        gym.make("SPL/ActiveVision-v0", camera_mode="magic")
