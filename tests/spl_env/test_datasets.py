"""Detector dataset generator: files, labels against the camera geometry, determinism."""

from __future__ import annotations

import json
import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from perception.geometry import project_points, range_bearing
from perception.types import CameraModel
from spl_env.datasets import DatasetConfig, generate
from spl_env.scenes.spl_field import SceneConfig

SCENE = SceneConfig()
CAMERA = CameraModel()
AIMED = DatasetConfig(aim_probability=1.0, occluder_probability=0.0)


def read_labels(folder: Path) -> list[dict]:
    return [json.loads(line) for line in (folder / "labels.jsonl").read_text().splitlines()]


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("poles")
    generate(AIMED, out, images=3, seed=4, scenes=1)
    return out


def test_files_and_meta(dataset: Path) -> None:
    records = read_labels(dataset)
    assert [r["image"] for r in records] == ["000000.png", "000001.png", "000002.png"]
    for record in records:
        image = cv2.imread(str(dataset / "images" / record["image"]))
        assert image is not None and image.shape == (CAMERA.height, CAMERA.width, 3)
    meta = json.loads((dataset / "meta.json").read_text())
    assert meta["classes"] == [
        "pole_pink_yellow",
        "pole_pink_green",
        "pole_pink_blue",
        "pole_yellow_pink",
        "pole_green_pink",
        "pole_blue_pink",
        "goal_post",
        "ball",
        "robot",
    ]
    assert meta["seed"] == 4 and meta["images"] == 3


def test_pole_labels_match_geometry(dataset: Path) -> None:
    poles = SCENE.poles.positions(SCENE.dimensions)
    junction_z = SCENE.poles.geometry.base_top_m + SCENE.poles.geometry.band_height_m
    seen = 0
    for record in read_labels(dataset):
        position = np.array(record["camera_world"]["position"])
        rotation = np.array(record["camera_world"]["rotation"])
        rb = range_bearing(record["robot_pose"], poles)
        for obj in record["objects"]:
            u0, v0, u1, v1 = obj["box"]
            assert 0 <= u0 <= u1 < CAMERA.width and 0 <= v0 <= v1 < CAMERA.height
            assert obj["pixels"] <= (u1 - u0 + 1) * (v1 - v0 + 1)
            i = obj["landmark_id"]
            if i is None:
                assert obj["class"] in ("goal_post", "ball", "robot") and obj["range_m"] is None
                continue
            assert obj["class_id"] == i
            assert obj["range_m"] == pytest.approx(rb[i, 0], abs=1e-9)
            assert obj["bearing_rad"] == pytest.approx(rb[i, 1], abs=1e-9)
            junction = np.array([*poles[i], junction_z])
            [(u, v)], _ = project_points(
                ((junction - position) @ rotation)[None], CAMERA.fx, CAMERA.fy, CAMERA.cx, CAMERA.cy
            )
            assert obj["keypoint"] == pytest.approx([u, v], abs=1e-6)
            if not obj["keypoint_visible"]:
                continue
            seen += 1
            # columns exact (pixel i covers u in [i - 0.5, i + 0.5]); rows up to 1 px off
            assert u0 - 0.5 <= u <= u1 + 0.5
            assert v0 - 1.5 <= v <= v1 + 1.5
            if not obj["truncated"] and obj["occluded_fraction"] == 0.0:
                # an unhidden upright pole's box is centred on its axis (sway tilts it a little)
                assert (u0 + u1) / 2 == pytest.approx(u, abs=1.5)
                height_px = CAMERA.fy * SCENE.poles.geometry.top_m / obj["range_m"]
                assert v1 - v0 + 1 == pytest.approx(height_px, rel=0.25)
    assert seen >= 2, "aimed frames should show poles"


def test_same_seed_same_frames(dataset: Path, tmp_path: Path) -> None:
    generate(AIMED, tmp_path, images=2, seed=4, scenes=1)
    assert read_labels(tmp_path) == read_labels(dataset)[:2]
    first = cv2.imread(str(dataset / "images" / "000001.png"))
    again = cv2.imread(str(tmp_path / "images" / "000001.png"))
    np.testing.assert_array_equal(first, again)


def test_bad_arguments_rejected(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="aim_probability"):
        DatasetConfig(aim_probability=1.5)
    with pytest.raises(ValueError, match="aim_range_m"):
        DatasetConfig(aim_range_m=(3.0, 1.0))
    with pytest.raises(ValueError, match="max_yaw_rate_rps"):
        DatasetConfig(max_yaw_rate_rps=math.inf)
    with pytest.raises(ValueError, match="scenes"):
        generate(DatasetConfig(), tmp_path, images=2, seed=0, scenes=3)
    with pytest.raises(ValueError, match="images"):
        generate(DatasetConfig(), tmp_path, images=0, seed=0, scenes=1)
