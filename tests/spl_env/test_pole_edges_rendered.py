"""Pole distance from band edges on rendered frames, against the labels' true range.

The truth is independent of the edge fit: the dataset generator's labels give each pole's true
range and bearing from the field layout and the camera's placed pose (the analytic, drawn-pole
checks of the same fit are in ``tests/perception/test_pole_edges.py``).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from perception.types import CameraState
from perception.vision.cnn_detector import vertical_lean
from perception.vision.pole_edges import PoleEdgeConfig, pole_edge_distance
from spl_env.datasets import DatasetConfig, generate
from spl_env.scenes.spl_field import SceneConfig
from spl_env.sensors.camera import CameraConfig

CAMERA = CameraConfig().model  # the generator's default camera
POLE = SceneConfig().poles.geometry  # and its default scene's poles
CONFIG = PoleEdgeConfig()


@pytest.fixture(scope="module")
def rendered(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("poles")
    config = DatasetConfig(
        aim_probability=1.0, occluder_probability=0.0, blur_probability=0.0, sway_probability=0.0
    )
    generate(config, out, images=20, seed=11, scenes=1)
    return out


def test_rendered_poles_measured_against_their_true_range(rendered: Path) -> None:
    """Label boxes and junctions of whole, unoccluded poles stand in for detections; the edge
    distance, turned into a range from the robot origin, matches the label's true range."""
    records = [json.loads(line) for line in (rendered / "labels.jsonl").read_text().splitlines()]
    errors = []
    for record in records:
        image = cv2.cvtColor(
            cv2.imread(str(rendered / "images" / record["image"])), cv2.COLOR_BGR2RGB
        )
        state = CameraState(
            position=np.array(record["camera_state"]["position"]),
            head_yaw=record["camera_state"]["head_yaw"],
            head_pitch=record["camera_state"]["head_pitch"],
            tilt=record["camera_state"]["tilt"],
        )
        rotation = state.rotation()
        for obj in record["objects"]:
            if obj["landmark_id"] is None or obj["truncated"] or obj["occluded_fraction"] > 0:
                continue
            if not obj["keypoint_visible"] or obj["range_m"] > 6.0:
                continue
            box = np.array(obj["box"], np.float64) + np.array([-0.5, -0.5, 0.5, 0.5])
            keypoint = np.array(obj["keypoint"])
            lean = vertical_lean(box, CAMERA, rotation)
            result = pole_edge_distance(
                image, box, keypoint, lean, CAMERA, rotation, state.position[2], POLE, CONFIG
            )
            if result is None:
                continue
            bearing = obj["bearing_rad"]
            axis = obj["range_m"] * np.array([math.cos(bearing), math.sin(bearing)])
            true_distance = float(np.linalg.norm(axis - state.position[:2]))
            errors.append(result.distance_m / true_distance - 1.0)
    assert len(errors) >= 6
    # each within 4 %, the mean within 1.5 % (the CNN's box extents give 3-5 % on average)
    assert np.max(np.abs(errors)) < 0.04
    assert abs(float(np.mean(errors))) < 0.015
