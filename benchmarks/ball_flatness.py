"""How flat the CNN's ball boxes are in the rendered striker: the fit of the flat-box check.

What: ``--episodes`` episodes of ``--env`` (``SPL/Striker-v0``, rendered: pixels and the CNN)
from ``reset(seed=--seed + k)``, played by the centre-kicking striker. After every step each
camera's frame (the top one, and the bottom one read at the pipeline's ``bottom_downscale``)
goes through the CNN again and :func:`perception.vision.cnn_ball.ball_sightings` with the
flat-box check off (every other step as in the pipeline); each sighting is placed on the
field with the *true* pose and labelled ``ball`` (within ``BALL_M`` of the true ball),
``mark`` (within ``MARK_M`` of a penalty mark) or ``other``, and its box's middle shading
measured (:func:`perception.vision.cnn_ball.middle_shading`: the luminance std of the box's
middle half; None where not judged). Reports per camera and label the count, the quantiles
of the shading, how many are not judged, and the share the default check
(``CnnBallConfig().min_shading_std``, whatever the env ran with) drops.

    python benchmarks/ball_flatness.py                      # tuning seeds 0-15, ~4 min
    python benchmarks/ball_flatness.py --set perception.cnn_ball.min_shading_std=null \
        --name ball_flatness_unchecked                      # the striker without the check

The striker plays on what its own pipeline believes: with the check (the default) it no
longer walks to the penalty mark it took for the ball, so the marks are seen less often; the
check's fit used the run without it.

Writes ``ball_flatness.json`` (``--name``) to ``--out`` (``benchmarks/results``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import add_overrides_argument, load_policy, parse_overrides, played_steps
from perception.types import BallSighting, CameraState
from perception.vision.cnn_ball import CnnBallConfig, ball_sightings, middle_shading
from perception.vision.cnn_detector import CnnPoleDetector
from spl_env.envs.core import SplEnv

RESULTS = Path("benchmarks/results")
BALL_M = 0.15  # a sighting this near the true ball is of the ball
MARK_M = 0.2  # ... else this near a penalty mark, of the mark
QUANTILES = (0, 1, 5, 25, 50, 75, 95, 100)


def labelled_sightings(
    sightings: tuple[BallSighting, ...], pose: np.ndarray, ball: np.ndarray, marks: np.ndarray
) -> list[tuple[BallSighting, str]]:
    """Each of ``sightings`` (robot frame) with its label, placed on the field by the true
    ``pose`` (3,) against the true ``ball`` (2,) and the penalty ``marks`` (2, 2)."""
    out = []
    x, y, theta = pose
    for s in sightings:
        phi = theta + s.bearing_rad
        point = np.array([x + s.range_m * math.cos(phi), y + s.range_m * math.sin(phi)])
        if math.dist(point, ball) < BALL_M:
            label = "ball"
        elif np.hypot(*(marks - point).T).min() < MARK_M:
            label = "mark"
        else:
            label = "other"
        out.append((s, label))
    return out


def camera_frames(core: SplEnv) -> list[tuple[str, np.ndarray, CameraState, int]]:
    """This step's frames as the ball's front end reads them: ``(name, image, camera state,
    downscale)`` of the top camera and, where rendered, the bottom one (read at the pipeline's
    ``bottom_downscale``)."""
    frame = core.sensor_frame
    frames = []
    if frame.image is not None and frame.camera_state is not None:
        frames.append(("top", frame.image, frame.camera_state, 1))
    if frame.bottom_image is not None and frame.bottom_camera_state is not None:
        downscale = core.config.perception.cnn_ball.bottom_downscale
        frames.append(("bottom", frame.bottom_image, frame.bottom_camera_state, downscale))
    return frames


def camera_sightings(
    detector: CnnPoleDetector,
    image: np.ndarray,
    state: CameraState,
    core: SplEnv,
    config: CnnBallConfig,
    downscale: int,
) -> tuple[BallSighting, ...]:
    """The ball sightings of one camera's ``image`` read at 1/``downscale`` with ``config``."""
    detections = (
        detector.detect_objects(image)
        if downscale == 1
        else detector.detect_objects_downscaled(image, downscale)
    )
    model = core.config.sensors.camera.model
    return ball_sightings(detections, model, state, config, downscale, image=image)


def summary(values: list[float | None], floor: float | None) -> dict[str, Any]:
    """Count, quantiles of the judged shadings, unjudged count, and the share ``floor`` drops."""
    judged = [v for v in values if v is not None]
    dropped = sum(v < floor for v in judged) if floor is not None else 0
    quantiles = np.percentile(judged, QUANTILES).tolist() if judged else None
    return {
        "count": len(values),
        "unjudged": len(values) - len(judged),
        "quantiles": dict(zip(QUANTILES, quantiles, strict=True)) if quantiles else None,
        "dropped_share": dropped / len(values),
    }


def episodes_parser(
    doc: str, name: str, env: str = "SPL/Striker-v0", player: str | None = None
) -> argparse.ArgumentParser:
    """The command line of the ball benchmarks that play episodes (``doc``'s first line their
    description): ``--env`` (``env``), ``--player`` where the script takes one (``player``
    its default), ``--seed`` 0, ``--episodes`` 16, ``--name`` (``name``), the env overrides
    and ``--out`` (``benchmarks/results``)."""
    parser = argparse.ArgumentParser(description=doc.split("\n")[0])
    parser.add_argument("--env", default=env)
    if player is not None:
        parser.add_argument("--player", default=player)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--episodes", type=int, default=16)
    parser.add_argument("--name", default=name)
    add_overrides_argument(parser)
    parser.add_argument("--out", type=Path, default=RESULTS)
    return parser


def made_env(args: argparse.Namespace) -> tuple[gym.Env, SplEnv]:
    """``args.env`` made with ``args.set``'s overrides (:func:`episodes_parser`), and its
    :class:`SplEnv` core (TypeError for an env of another kind)."""
    env = gym.make(args.env, **parse_overrides(args.set))
    core = env.unwrapped
    if not isinstance(core, SplEnv):
        raise TypeError(f"expected an SplEnv, got {type(core).__name__}")
    return env, core


def written_result(
    args: argparse.Namespace, player: str, measured: dict[str, Any], start_s: float
) -> dict[str, Any]:
    """The result of an episodes benchmark (:func:`episodes_parser`): its run (env, seeds,
    ``player``, overrides), ``measured`` and the seconds since ``start_s``
    (``time.perf_counter``); written to ``--out``/``--name``.json and returned."""
    result = {
        "env_id": args.env,
        "seeds": [args.seed, args.seed + args.episodes - 1],
        "player": player,
        "overrides": args.set,
        **measured,
        "run_s": time.perf_counter() - start_s,
    }
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / f"{args.name}.json").write_text(json.dumps(result, indent=1))
    return result


def main() -> None:
    parser = episodes_parser(__doc__, "ball_flatness")
    args = parser.parse_args()
    torch.set_num_threads(1)
    start = time.perf_counter()
    env, core = made_env(args)
    pipeline = core.config.perception
    unjudged = dataclasses.replace(pipeline.cnn_ball, min_shading_std=None)
    detector = core.perception_context.cnn_detector(pipeline.cnn)
    marks = core.scene.dimensions.penalty_marks()
    policy = load_policy("centre_kick", env.get_wrapper_attr("config"))
    shading: dict[str, list[float | None]] = defaultdict(list)
    for seed in range(args.seed, args.seed + args.episodes):
        for _ in played_steps(env, policy, seed):
            truth = core.world_state
            for name, image, state, downscale in camera_frames(core):
                found = camera_sightings(detector, image, state, core, unjudged, downscale)
                for sighting, label in labelled_sightings(
                    found, truth.robot_pose, truth.ball, marks
                ):
                    value = middle_shading(image, sighting.box, pipeline.cnn_ball)
                    shading[f"{name}/{label}"].append(value)
    env.close()
    floor = CnnBallConfig().min_shading_std  # the default check's, whatever the env ran with
    measured = {
        "min_shading_std": floor,
        "by_camera_and_label": {k: summary(v, floor) for k, v in sorted(shading.items())},
    }
    result = written_result(args, "centre_kick", measured, start)
    print(json.dumps(result["by_camera_and_label"], indent=1))


if __name__ == "__main__":
    main()
