import json
from pathlib import Path

import cv2
import pytest

from agents.evaluate import main as evaluate_main
from agents.evaluate import model_files, pretrained_names, training_config
from agents.options import OptionPolicy


def test_the_active_vision_policy_is_shipped_small_with_its_config() -> None:
    assert "active_vision" in pretrained_names()
    files = model_files("pretrained:active_vision")
    assert files is not None and files[1] is not None
    model, config = files
    assert model.stat().st_size < 1_000_000
    saved = json.loads(config.read_text())
    assert saved["env_id"] == "SPL/ActiveVision-v1"
    assert saved["options"] == "head"
    assert training_config("pretrained:active_vision") == saved


def test_unknown_pretrained_name_is_refused_with_the_shipped_names() -> None:
    with pytest.raises(ValueError, match="active_vision"):
        model_files("pretrained:nonsense")


def test_evaluate_runs_the_pretrained_policy_on_its_env_and_writes_a_video(
    tmp_path: Path,
) -> None:
    args = ["--policy", "pretrained:active_vision", "--episodes", "1", "--video"]
    evaluate_main([*args, "--out", str(tmp_path), "--set", "episode_s=2"])
    result = json.loads((tmp_path / "metrics.json").read_text())
    assert result["env"] == "SPL/ActiveVision-v1"  # the model's env, not the default v0
    assert result["episodes"][0]["steps"] == 20
    video = cv2.VideoCapture(str(tmp_path / "episode.mp4"))
    assert video.get(cv2.CAP_PROP_FRAME_COUNT) == 20
    assert video.get(cv2.CAP_PROP_FPS) == pytest.approx(10.0)
    video.release()


def test_load_policy_gives_an_option_policy_for_the_shipped_model() -> None:
    import gymnasium as gym

    from agents.evaluate import env_kwargs_for, load_policy

    env = gym.make("SPL/ActiveVision-v1", **env_kwargs_for("pretrained:active_vision", {}))
    policy = load_policy("pretrained:active_vision", env.get_wrapper_attr("config"))
    assert isinstance(policy, OptionPolicy)
    obs, _ = env.reset(seed=0)
    action, _ = policy.predict(obs)
    assert env.action_space.contains(action)
    env.close()


def test_the_shipped_head_policy_is_refused_on_a_soccer_env() -> None:
    import gymnasium as gym

    from agents.evaluate import load_policy

    env = gym.make("SPL/PenaltyShootout-v0", camera_mode="geometric", frontend="colour")
    with pytest.raises(ValueError, match="trained on head options; it cannot play this soccer"):
        load_policy("pretrained:active_vision", env.get_wrapper_attr("config"))
    env.close()


def test_the_striker_is_shipped_small_and_evaluates_in_its_env(tmp_path: Path) -> None:
    assert "striker" in pretrained_names()
    files = model_files("pretrained:striker")
    assert files is not None and files[1] is not None
    assert files[0].stat().st_size < 1_000_000
    saved = training_config("pretrained:striker")
    assert saved["env_id"] == "SPL/Striker-v0" and saved["options"] == "striker"
    args = ["--policy", "pretrained:striker", "--episodes", "1", "--out", str(tmp_path)]
    evaluate_main([*args, "--set", "episode_s=2"])
    result = json.loads((tmp_path / "metrics.json").read_text())
    assert result["env"] == "SPL/Striker-v0"
    assert result["episodes"][0]["scored"] in (0.0, 1.0)
