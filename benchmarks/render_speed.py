"""Render time per camera frame of the SPL scene, an earlier scene and today's side by side.

    git worktree add /tmp/wt_render <earlier commit>
    python benchmarks/render_speed.py --baseline /tmp/wt_render/spl_env/scenes/spl_field.py

For each env id of ``--envs`` two envs are made in this one process: one whose scene the
baseline module's ``SplFieldScene`` builds ("before"), one with today's ("after"); everything
else is today's code. Both are reset with the same seeds and stepped with the same random
actions, alternately (which of them steps first alternates too). Timed per step: the wall time
``info["timing"]["render"]`` (the camera's frame: ``getCameraImage`` and the image-formation
effects, the part of a step the scene decides), and the CPU time of the same calls
(``time.thread_time`` around each env's ``Camera.render``: PyBullet's ``DIRECT`` client renders
in the calling thread), which other jobs on a shared CPU disturb less. Every
``--compare-every`` steps both envs render a noise-free view of the same state
(``NaoRig.camera_view``), compared by the mean absolute pixel difference (8-bit levels), the
share of pixels that differ at all, and what the detectors find in each: the CNN's objects
(matched by class and box IoU >= 0.5), field features (matched by kind, points within
``FEATURE_TOL_M``) and horizon features (1D SURF, matched by column within
``HORIZON_TOL_PX``). Without ``--baseline`` only today's scene is timed. The CPU is shared:
quote the ratios, which both envs' interleaved steps share.
Writes ``benchmarks/results/render_speed.json``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import platform
import sys
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import ModuleType
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

import spl_env  # noqa: F401  (registers the env ids)
import spl_env.envs.core as core
from perception.landmarks.horizon_features import HorizonFeatureConfig, horizon_features
from perception.types import CameraModel, CameraState
from perception.vision.cnn_detector import CnnDetectorConfig, CnnPoleDetector, box_iou
from perception.vision.field_features import detect_field_features

ENVS = ("SPL/ActiveVision-v1", "SPL/ActiveVision-NoPoles-v1")
FEATURE_TOL_M = 0.05  # a field feature's points this close (m) match
HORIZON_TOL_PX = 0.5  # a horizon feature this close (px, along the row) matches
IOU_MATCH = 0.5  # a CNN object matches one of its class with this box IoU


def load_scene_module(path: Path) -> ModuleType:
    """The scene module (``spl_field.py``) at ``path``, imported under its own name."""
    spec = importlib.util.spec_from_file_location("baseline_spl_field", path)
    if spec is None or spec.loader is None:
        raise ValueError(f"--baseline must be a Python file, got {path}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up while it loads
    spec.loader.exec_module(module)
    return module


@contextmanager
def scene_class(module: ModuleType | None) -> Iterator[None]:
    """Envs made inside build their scene with ``module``'s ``SplFieldScene`` (today's: None)."""
    today = core.SplFieldScene
    if module is not None:
        core.SplFieldScene = module.SplFieldScene  # type: ignore[misc]
    try:
        yield
    finally:
        core.SplFieldScene = today  # type: ignore[misc]


class Detectors:
    """The CNN, the field-feature detector and the horizon features, on one camera."""

    def __init__(self, env: gym.Env) -> None:
        u: Any = env.unwrapped
        self.camera: CameraModel = u.rig.config.camera.model
        scene = u.scene
        self.cnn = CnnPoleDetector(
            CnnDetectorConfig(), self.camera, scene.codes, scene.config.poles.geometry
        )
        self.horizon = HorizonFeatureConfig()

    def compare(
        self, before: NDArray[np.uint8], after: NDArray[np.uint8], state: CameraState
    ) -> dict[str, int]:
        """Counts of what each image gives and of what matches between them."""
        objects = [self.cnn.detect_objects(image) for image in (before, after)]
        features = [detect_field_features(im, self.camera, state) for im in (before, after)]
        horizon = [horizon_features(im, self.camera, state, self.horizon) for im in (before, after)]
        return {
            "cnn_before": len(objects[0]),
            "cnn_after": len(objects[1]),
            "cnn_matched": _matched(
                objects[0],
                objects[1],
                lambda a, b: a.class_id == b.class_id and box_iou(a.box, b.box) >= IOU_MATCH,
            ),
            "features_before": len(features[0]),
            "features_after": len(features[1]),
            "features_matched": _matched(
                features[0],
                features[1],
                lambda a, b: (
                    a.kind == b.kind
                    and a.points.shape == b.points.shape
                    and bool(np.all(np.hypot(*(a.points - b.points).T) <= FEATURE_TOL_M))
                ),
            ),
            "horizon_before": len(horizon[0]),
            "horizon_after": len(horizon[1]),
            "horizon_matched": _matched(
                list(horizon[0].features.x),
                list(horizon[1].features.x),
                lambda a, b: abs(a - b) <= HORIZON_TOL_PX,
            ),
        }


class CpuTimer:
    """Records the CPU seconds of each call of ``camera``'s ``render`` (wrapped in place)."""

    def __init__(self, camera: Any) -> None:
        self.seconds: list[float] = []
        self._render = camera.render
        camera.render = self

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        start = time.thread_time()
        result = self._render(*args, **kwargs)
        self.seconds.append(time.thread_time() - start)
        return result


def _matched(before: Sequence[Any], after: Sequence[Any], same: Any) -> int:
    """Greedy one-to-one matches between ``before`` and ``after`` under ``same(a, b)``."""
    free = list(after)
    count = 0
    for a in before:
        hit = next((k for k, b in enumerate(free) if same(a, b)), None)
        if hit is not None:
            del free[hit]
            count += 1
    return count


def measure(
    env_id: str, baseline: ModuleType | None, seeds: int, steps: int, compare_every: int
) -> dict[str, Any]:
    """Render ms per frame of each scene over ``seeds`` episodes of ``steps`` steps, and the
    comparison of the noise-free views every ``compare_every`` steps."""
    sides = ("before", "after") if baseline is not None else ("after",)
    envs = {}
    for side in sides:
        with scene_class(baseline if side == "before" else None):
            envs[side] = gym.make(env_id, info_timing=True)
    cpu = {side: CpuTimer(_unwrapped(env).rig.camera) for side, env in envs.items()}
    detectors = Detectors(envs["after"]) if baseline is not None else None
    render_s: dict[str, list[float]] = {side: [] for side in sides}
    pixels: list[dict[str, float]] = []
    counts: dict[str, int] = {}
    for seed in range(seeds):
        for env in envs.values():
            env.reset(seed=seed)
        actions = envs["after"].action_space
        actions.seed(seed)
        for k in range(steps):
            action = actions.sample()
            order = sides if k % 2 == 0 else sides[::-1]
            for side in order:
                *_, info = envs[side].step(action)
                render_s[side].append(info["timing"]["render"])
            if detectors is not None and k % compare_every == 0:
                views = {s: _quiet_view(e) for s, e in envs.items()}
                pixels.append(_pixel_difference(views["before"], views["after"]))
                state = _unwrapped(envs["after"]).rig.robot.camera_state()
                for name, n in detectors.compare(views["before"], views["after"], state).items():
                    counts[name] = counts.get(name, 0) + n
    for env in envs.values():
        env.close()
    cpu_s = {side: timer.seconds for side, timer in cpu.items()}
    return _summary(env_id, render_s, cpu_s, pixels, counts)


def _unwrapped(env: gym.Env) -> Any:
    """The env under its wrappers (an SPL env core)."""
    return env.unwrapped


def _quiet_view(env: gym.Env) -> NDArray[np.uint8]:
    """The noise-free frame (H, W, 3) of the env's camera now."""
    u = _unwrapped(env)
    image: NDArray[np.uint8] = u.rig.camera_view(u.world)[0]
    return image


def _pixel_difference(before: NDArray[np.uint8], after: NDArray[np.uint8]) -> dict[str, float]:
    """Mean absolute difference (8-bit levels) and the share of pixels differing at all."""
    diff = np.abs(before.astype(np.int16) - after.astype(np.int16))
    return {"mean_abs": float(diff.mean()), "share_differing": float((diff.max(axis=2) > 0).mean())}


def _summary(
    env_id: str,
    render_s: dict[str, list[float]],
    cpu_s: dict[str, list[float]],
    pixels: list[dict[str, float]],
    counts: dict[str, int],
) -> dict[str, Any]:
    """The timings' means and medians (ms), their ratios, the image and detector comparisons."""
    ms = {side: 1000 * np.asarray(times) for side, times in render_s.items()}
    cpu_ms = {side: 1000 * np.asarray(times) for side, times in cpu_s.items()}
    result: dict[str, Any] = {
        "env_id": env_id,
        "frames": len(ms["after"]),
        "render_ms_mean": {side: float(t.mean()) for side, t in ms.items()},
        "render_ms_median": {side: float(np.median(t)) for side, t in ms.items()},
        "render_cpu_ms_mean": {side: float(t.mean()) for side, t in cpu_ms.items()},
    }
    if "before" in ms:
        result["after_over_before"] = float(ms["after"].sum() / ms["before"].sum())
        result["cpu_after_over_before"] = float(cpu_ms["after"].sum() / cpu_ms["before"].sum())
        result["images"] = {
            "compared": len(pixels),
            "mean_abs_difference": float(np.mean([p["mean_abs"] for p in pixels])),
            "max_mean_abs_difference": float(np.max([p["mean_abs"] for p in pixels])),
            "share_pixels_differing": float(np.mean([p["share_differing"] for p in pixels])),
        }
        result["detections"] = counts
    return result


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--baseline", type=Path, default=None, help="an earlier spl_field.py")
    parser.add_argument("--envs", nargs="+", default=list(ENVS))
    parser.add_argument("--seeds", type=int, default=4, help="episodes per env (seeds 0..)")
    parser.add_argument("--steps", type=int, default=50, help="steps per episode")
    parser.add_argument("--compare-every", type=int, default=1, help="steps between comparisons")
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/render_speed.json"))
    args = parser.parse_args()
    baseline = load_scene_module(args.baseline) if args.baseline is not None else None
    runs = [
        measure(env_id, baseline, args.seeds, args.steps, args.compare_every)
        for env_id in args.envs
    ]
    result = {
        "machine": {"cpu_count": os.cpu_count(), "python": platform.python_version()},
        "setting": {
            "baseline": str(args.baseline) if args.baseline else None,
            "seeds": args.seeds,
            "steps": args.steps,
            "compare_every": args.compare_every,
        },
        "runs": runs,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
