"""Learn the visual vocabulary of horizon features (seed 004 §4.2) from rendered SPL frames.

``python -m training.learn_vocabulary --out perception/landmarks/words/horizon_words.npz``
(defaults: training scenes 1000-1029, 40 frames each, K = 200, SFF, bottom 5 % stopped, seed 0;
36-65 s on 2 shared CPU cores, two thirds of it rendering).

1. For each training scene seed (``--first-scene`` onwards; never the reporting seeds 100-199)
   builds the field as the envs do (:class:`spl_env.scenes.spl_field.SplFieldScene` with
   ``SceneConfig(poles_enabled=False, scene_seed=s, poster_set=...)``: the seed's field, the
   scene's posters, of the ``classic`` and ``textured`` sets by turns, so that one vocabulary
   serves both)
   with our robot alone: features on other robots are discarded before quantisation (seed 004
   §4.2), so the vocabulary describes the background.
2. Renders ``--frames`` frames per scene, drawn from one generator seeded by ``(--seed, s)``:
   the robot anywhere inside the field lines facing anywhere, head yaw in ±``HEAD_YAW_RAD``
   and pitch in ``HEAD_PITCH_RAD`` (the horizon stays in the image), lighting drawn as
   :meth:`spl_env.sensors.camera.EpisodeLighting.sample` (even default lighting in
   ``DEFAULT_LIGHTING_PROBABILITY`` of the frames), the camera's default sensor noise.
3. Extracts each frame's horizon features
   (:func:`perception.landmarks.horizon_features.horizon_features`, default config, with the
   camera model and the camera state the joints report), pools the descriptors, learns K words
   by k-means with SFF initialisation (:func:`perception.landmarks.vocabulary.learn_vocabulary`,
   generator seeded by ``--seed``), stops the bottom ``--bottom`` (and top ``--top``) fraction
   of words by training frequency and saves the vocabulary to ``--out``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from perception.geometry import FloatArray
from perception.landmarks.horizon_features import HorizonFeatureConfig, horizon_features
from perception.landmarks.vocabulary import learn_vocabulary, with_stop_list
from spl_env.robots.nao import NaoRobot, RobotConfig
from spl_env.scenes.spl_field import SceneConfig, SplFieldScene
from spl_env.sensors.camera import Camera, CameraConfig, EpisodeLighting, LightingRandomisation
from spl_env.sim.world import BulletWorld

HEAD_YAW_RAD = 1.2  # head yaw drawn in ±this
HEAD_PITCH_RAD = (-0.15, 0.3)  # head pitch range (rad, positive looks down): horizon in view
DEFAULT_LIGHTING_PROBABILITY = 0.2  # frames under even default lighting
REPORTING_SEEDS = range(100, 200)  # scene seeds of reported results: never trained on
POSTER_SET_TURNS = ("classic", "textured")  # scene seed s takes set s % 2


def scene_descriptors(scene_seed: int, frames: int, seed: int) -> tuple[FloatArray, int]:
    """The pooled horizon-feature descriptors (M, 6) of ``frames`` frames of scene
    ``scene_seed`` (module docstring, step 2) and the number of frames that had features."""
    rng = np.random.default_rng([seed, scene_seed])
    world = BulletWorld(time_step_s=0.01)
    try:
        poster_set = POSTER_SET_TURNS[scene_seed % len(POSTER_SET_TURNS)]
        scene = SplFieldScene(
            world,
            SceneConfig(poles_enabled=False, scene_seed=scene_seed, poster_set=poster_set),
        )
        robot = NaoRobot(world, "self", team=0, config=RobotConfig())
        camera_config = CameraConfig()
        camera, model = Camera(camera_config), camera_config.model
        dims = scene.dimensions
        features_config = HorizonFeatureConfig()
        pooled, seen = [], 0
        for _ in range(frames):
            pose = np.array(
                [
                    rng.uniform(-dims.half_length_m, dims.half_length_m),
                    rng.uniform(-dims.half_width_m, dims.half_width_m),
                    rng.uniform(-np.pi, np.pi),
                ]
            )
            head = np.array(
                [rng.uniform(-HEAD_YAW_RAD, HEAD_YAW_RAD), rng.uniform(*HEAD_PITCH_RAD)]
            )
            robot.place(pose, head=head)
            lighting = (
                EpisodeLighting.default()
                if rng.uniform() < DEFAULT_LIGHTING_PROBABILITY
                else EpisodeLighting.sample(LightingRandomisation(), rng)
            )
            image, _ = camera.render(world, *robot.camera_pose_world(), lighting, rng)
            found = horizon_features(image, model, robot.camera_state(), features_config)
            pooled.append(found.features.descriptors)
            seen += len(found) > 0
        return np.concatenate(pooled), seen
    finally:
        world.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, required=True, help="vocabulary .npz to write")
    parser.add_argument("--first-scene", type=int, default=1000, help="first training scene seed")
    parser.add_argument("--scenes", type=int, default=30, help="number of training scenes")
    parser.add_argument("--frames", type=int, default=40, help="frames per scene")
    parser.add_argument("--k", type=int, default=200, help="words (seed 004 §4.2: 200)")
    parser.add_argument("--bottom", type=float, default=0.05, help="least frequent words stopped")
    parser.add_argument("--top", type=float, default=0.0, help="most frequent words stopped")
    parser.add_argument("--iterations", type=int, default=300, help="Lloyd iterations, at most")
    parser.add_argument("--seed", type=int, default=0, help="seed of every random draw")
    args = parser.parse_args()
    scene_seeds = range(args.first_scene, args.first_scene + args.scenes)
    if set(scene_seeds) & set(REPORTING_SEEDS):
        parser.error(f"scene seeds {scene_seeds} overlap the reporting seeds {REPORTING_SEEDS}")
    start = time.perf_counter()
    pooled, frames = [], 0
    for scene_seed in scene_seeds:
        descriptors, seen = scene_descriptors(scene_seed, args.frames, args.seed)
        pooled.append(descriptors)
        frames += seen
    descriptors = np.concatenate(pooled)
    rendered = time.perf_counter() - start
    print(
        f"{args.scenes} scenes x {args.frames} frames ({frames} with features): "
        f"{len(descriptors)} descriptors in {rendered:.1f} s",
        flush=True,
    )
    rng = np.random.default_rng(args.seed)
    words = learn_vocabulary(descriptors, args.k, rng=rng, init="sff", iterations=args.iterations)
    vocabulary = with_stop_list(words, descriptors, bottom=args.bottom, top=args.top)
    counts = np.bincount(vocabulary.quantise(descriptors), minlength=args.k)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    vocabulary.save(args.out)
    print(
        f"{args.k} words ({int(vocabulary.stopped.sum())} stopped), descriptors per word "
        f"{counts.min()}..{counts.max()} (median {np.median(counts):.0f}); saved {args.out} "
        f"after {time.perf_counter() - start:.1f} s"
    )


if __name__ == "__main__":
    main()
