"""Recording an episode's sightings and replaying them reproduces the live filter."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import load_policy, run_episode
from agents.recording import frontends_for, record_episode
from perception.replay import replay


@pytest.mark.parametrize("backend", ["classic", "fej"])
def test_replay_of_a_recording_matches_the_live_filter(backend: str) -> None:
    env = gym.make(
        "SPL/ActiveVision-v0",
        camera_mode="geometric",
        frontend="colour",
        episode_s=8.0,
        backend=backend,
        min_views=2,
    )
    config = env.get_wrapper_attr("config")
    policy = load_policy("scan", config)
    live = run_episode(env, policy, seed=5)
    log = record_episode(env, load_policy("scan", config), 5, frontends_for(env, ("colour",)))
    env.close()
    assert sum(len(s) for s in log.sightings["colour"]) > 10  # the poles were seen
    np.testing.assert_array_equal(log.true_poses, np.array(live.true_poses))
    result = replay(log, "colour", config.perception.slam)
    np.testing.assert_allclose(result.poses, np.array(live.slam_poses), atol=1e-12)


def test_rendered_recording_runs_every_front_end_on_the_envs_frames() -> None:
    env = gym.make("SPL/ActiveVision-v0", frontend="colour", episode_s=3.0)
    config = env.get_wrapper_attr("config")
    live = run_episode(env, load_policy("scan", config), seed=2)
    frontends = frontends_for(env, ("colour", "cnn"))
    log = record_episode(env, load_policy("scan", config), 2, frontends)
    env.close()
    assert all(sum(len(s) for s in log.sightings[name]) > 5 for name in ("colour", "cnn"))
    result = replay(log, "colour", config.perception.slam)
    np.testing.assert_allclose(result.poses, np.array(live.slam_poses), atol=1e-12)


def test_recording_needs_an_spl_env() -> None:
    env = gym.make("CartPole-v1")
    with pytest.raises(TypeError, match="SplEnv"):
        frontends_for(env, ("colour",))


@pytest.mark.parametrize(("frontend", "missing"), [("cnn", "image"), ("oracle", "truth")])
def test_a_front_end_reading_what_the_frames_lack_is_refused(frontend: str, missing: str) -> None:
    # the geometric camera renders no image, and the colour front end asks for no truth
    env = gym.make("SPL/ActiveVision-v0", camera_mode="geometric", frontend="colour", episode_s=1.0)
    with pytest.raises(ValueError, match=rf"front end '{frontend}' reads frame\.\['{missing}'\]"):
        frontends_for(env, (frontend,))
    with pytest.raises(ValueError, match=f"'{frontend}'"):  # also among front ends it can record
        frontends_for(env, ("colour", frontend))
    # the env's own front end records its own sightings: no pipeline of its own
    assert frontends_for(env, ("colour",)) == {"colour": None}
    env.close()
