"""Time per 320 x 240 frame of the CNN pole detector on one CPU thread.

Renders ``--frames`` held-out frames (``spl_env.datasets``, randomised lighting) and times, per
frame, after ``--warmup`` passes over them:

- ``network``: the image tensor and the forward pass;
- ``detect_objects``: plus decoding the detections of every class (the inference);
- ``detect``: plus each pole's range and bearing (band edges or box extents), what the
  front end costs per frame.

Each frame is run ``--repeats`` times; the mean, median and 95th percentile are reported.
Writes ``--out`` (default ``benchmarks/results/cnn_speed.json``).

Usage::

    python benchmarks/cnn_speed.py --frames 100 --repeats 5
"""

from __future__ import annotations

import argparse
import json
import platform
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import torch

from perception.types import CameraModel, CameraState, PoleCode, PoleGeometry
from perception.vision import CnnDetectorConfig, CnnPoleDetector
from perception.vision.cnn_model import image_tensor
from spl_env.datasets import DatasetConfig, generate

RESULTS = Path("benchmarks/results")


def frames(count: int, seed: int) -> tuple[list[np.ndarray], list[CameraState], dict[str, Any]]:
    """``count`` rendered RGB frames, their camera states and the dataset's meta."""
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        generate(DatasetConfig(), out, images=count, seed=seed, scenes=1)
        meta = json.loads((out / "meta.json").read_text())
        images, states = [], []
        for line in (out / "labels.jsonl").read_text().splitlines():
            record = json.loads(line)
            bgr = cv2.imread(str(out / "images" / record["image"]))
            images.append(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))
            state = record["camera_state"]
            states.append(
                CameraState(
                    position=np.array(state["position"]),
                    head_yaw=state["head_yaw"],
                    head_pitch=state["head_pitch"],
                    tilt=state["tilt"],
                )
            )
    return images, states, meta


def timed(step: Callable[[int], object], count: int, repeats: int, warmup: int) -> list[float]:
    """Seconds of ``step(k)`` for every frame k, ``repeats`` times, after ``warmup`` passes."""
    for _ in range(warmup):
        for k in range(count):
            step(k)
    times = []
    for _ in range(repeats):
        for k in range(count):
            start = time.perf_counter()
            step(k)
            times.append(time.perf_counter() - start)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--warmup", type=int, default=1)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--out", type=Path, default=RESULTS / "cnn_speed.json")
    args = parser.parse_args()
    torch.set_num_threads(1)
    images, states, meta = frames(args.frames, args.seed)
    camera = CameraModel(**meta["camera"])
    codes = [PoleCode(**code) for code in meta["pole_codes"]]
    detector = CnnPoleDetector(CnnDetectorConfig(), camera, codes, PoleGeometry())
    network = detector.network

    def forward(k: int) -> object:
        with torch.inference_mode():
            return network(image_tensor(images[k][None]))

    steps = {
        "network": forward,
        "detect_objects": lambda k: detector.detect_objects(images[k]),
        "detect": lambda k: detector.detect(images[k], states[k]),
    }
    report: dict[str, Any] = {
        "frames": args.frames,
        "repeats": args.repeats,
        "threads": torch.get_num_threads(),
        "torch": torch.__version__,
        "machine": platform.machine(),
        "processor": platform.processor(),
        "poles_per_frame": float(
            np.mean([len(detector.detect(im, st)) for im, st in zip(images, states, strict=True)])
        ),
    }
    for name, step in steps.items():
        ms = 1e3 * np.array(timed(step, args.frames, args.repeats, args.warmup))
        report[name] = {
            "ms_mean": float(ms.mean()),
            "ms_median": float(np.median(ms)),
            "ms_p95": float(np.percentile(ms, 95)),
        }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=1) + "\n")
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
