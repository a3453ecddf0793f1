"""Write evaluation frames to an MP4 video with OpenCV's ``VideoWriter``.

    write_video(frames, Path("episode.mp4"), fps=10.0)

Frames are the RGB arrays (H, W, 3) uint8 that ``env.render()`` returns with
``render_mode="rgb_array"``; every frame must have the first one's size.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np


def write_video(frames: Sequence[np.ndarray], path: Path, fps: float) -> Path:
    """Encode ``frames`` (RGB, (H, W, 3) uint8 each) at ``fps`` frames per second into the MP4
    file ``path`` (codec ``mp4v``); returns ``path``."""
    if path.suffix.lower() != ".mp4":
        raise ValueError(f"path must end in .mp4, got {str(path)!r}")
    if not (math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be finite and > 0, got {fps}")
    if len(frames) == 0:
        raise ValueError("frames must hold at least one frame, got none")
    first = np.asarray(frames[0])
    if first.ndim != 3 or first.shape[2] != 3 or first.dtype != np.uint8:
        raise ValueError(f"frames must be (H, W, 3) uint8 RGB, got {first.shape} {first.dtype}")
    height, width = first.shape[:2]
    path.parent.mkdir(parents=True, exist_ok=True)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), fps, (width, height))
    if not writer.isOpened():
        raise RuntimeError(f"OpenCV could not open an mp4v video writer for {path}")
    try:
        for k, frame in enumerate(frames):
            image = np.asarray(frame)
            if image.shape != first.shape or image.dtype != np.uint8:
                raise ValueError(
                    f"frames[{k}] is {image.shape} {image.dtype}, the first {first.shape} uint8"
                )
            writer.write(cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
    finally:
        writer.release()
    return path
