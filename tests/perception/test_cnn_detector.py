"""CNN pole detector: heatmap decoding, range law, bearing, bad input and the packaged weights."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
import torch

from perception.geometry import project_points
from perception.types import CameraModel, CameraState, PoleCode, PoleGeometry
from perception.vision import CnnDetectorConfig, CnnPoleDetector, Detection, cnn_model
from perception.vision.cnn_detector import (
    PoleExtents,
    PoleRangeModel,
    PowerLaw,
    default_weights,
    load_network,
    pole_extents,
    pole_range_bearing,
)
from perception.vision.cnn_model import (
    N_REGRESSION,
    STRIDE,
    Decoded,
    NetConfig,
    PoleNet,
    decode,
    encode,
    fuse_batch_norms,
)
from training.train_detector import TrainConfig, save

CAMERA = CameraModel()
POLE = PoleGeometry()
CODES = tuple(
    [
        PoleCode(landmark_id=i, top="pink", bottom=c)
        for i, c in enumerate(("yellow", "green", "blue"))
    ]
    + [
        PoleCode(landmark_id=3 + i, top=c, bottom="pink")
        for i, c in enumerate(("yellow", "green", "blue"))
    ]
)
N_CLASSES = 9
GRID = (CAMERA.height // STRIDE, CAMERA.width // STRIDE)
MODEL = PoleRangeModel(
    laws={
        "height": PowerLaw(a=240.0, b=1.0),  # 48 px tall: 5 m
        "top": PowerLaw(a=60.0, b=1.0),  # 12 px from the junction to the top: 5 m
        "bottom": PowerLaw(a=180.0, b=1.0),
        "width": PowerLaw(a=30.0, b=1.0),  # 6 px wide: 5 m
    },
    aspect_law=PowerLaw(a=0.125, b=0.0),  # width = height / 8
    aspect_margin=0.2,
    rel_var={
        "height": (1e-4, 0.5),
        "top": (2e-4, 1.0),
        "bottom": (3e-4, 1.5),
        "width": (4e-4, 2.0),
    },
    bearing_std_px=1.5,
)


def blank_output() -> np.ndarray:
    """Raw network output (C + 6, h, w) with no object anywhere."""
    out = np.zeros((N_CLASSES + N_REGRESSION, *GRID), np.float32)
    out[:N_CLASSES] = -10.0
    return out


def test_decode_hand_made_heatmap() -> None:
    out = blank_output()
    out[2, 5, 7] = 3.0  # pole class 2, peak probability sigmoid(3) = 0.953
    out[N_CLASSES:, 5, 7] = [0.25, 0.75, math.log(2), math.log(1), 0, math.log(4)]
    out[2, 5, 8] = 2.0  # lower neighbour in the same class: suppressed
    out[8, 5, 8] = 1.0  # same cell in another class (robot, 0.731): kept
    out[7, 20, 30] = -1.0  # ball below the threshold (0.269)
    found = decode(out, N_CLASSES, score_threshold=0.3, max_detections=10)
    np.testing.assert_array_equal(found.class_ids, [2, 8])
    np.testing.assert_allclose(
        found.scores, [1 / (1 + math.exp(-3)), 1 / (1 + math.exp(-1))], rtol=1e-6
    )
    u, v = (7 + 0.25) * STRIDE - 0.5, (5 + 0.75) * STRIDE - 0.5
    np.testing.assert_allclose(found.keypoints[0], [u, v])
    np.testing.assert_allclose(found.boxes[0], [u - 16, v - 8, u + 8, v + 32], atol=1e-5)
    np.testing.assert_allclose(found.keypoints[1], [8 * STRIDE - 0.5, 5 * STRIDE - 0.5])
    assert len(decode(out, N_CLASSES, score_threshold=0.3, max_detections=1).class_ids) == 1


def test_encode_then_decode_round_trip() -> None:
    keypoints = np.array([[100.3, 60.8], [250.0, 200.0]])
    boxes = np.array([[95.0, 40.0, 106.0, 140.0], [230.0, 180.0, 270.0, 220.0]])
    targets = encode(
        [4, 8], keypoints, boxes, [(7, np.array([0.0, 0.0, 30.0, 30.0]))], N_CLASSES, GRID
    )
    assert targets.heatmap.max() == 1.0 and (targets.heatmap == 1.0).sum() == 2
    assert targets.weight[7, :4, :4].sum() == 0 and targets.weight[6, :4, :4].all()
    out = blank_output()
    for (c, row, col), reg in zip(targets.cells, targets.regression, strict=True):
        out[c, row, col] = 5.0
        out[N_CLASSES:, row, col] = reg
    found = decode(out, N_CLASSES, score_threshold=0.5, max_detections=10)
    order = np.argsort(found.class_ids)
    np.testing.assert_array_equal(found.class_ids[order], [4, 8])
    np.testing.assert_allclose(found.keypoints[order], keypoints, atol=1e-4)
    np.testing.assert_allclose(found.boxes[order], boxes, atol=1e-4)


def extents(box: list[float], top: float, bottom: float) -> tuple[PoleExtents, np.ndarray]:
    """Extents of an upright box (4,) pixel edges with the junction ``top`` px below its top."""
    b = np.array(box)
    return PoleExtents(width=b[2] - b[0], height=b[3] - b[1], top=top, bottom=bottom), b


@pytest.mark.parametrize(
    ("box", "top", "bottom", "branch", "distance", "rel_var"),
    [
        # 6 x 48 px, as tall as its width says: the height, 240 / 48
        ([100.0, 50.0, 106.0, 98.0], 12.0, 36.0, "height", 5.0, 1e-4 + 0.5 / 48**2),
        # aspect 1/7, within the margin: still the height
        ([100.0, 50.0, 106.0, 92.0], 12.0, 30.0, "height", 240 / 42, 1e-4 + 0.5 / 42**2),
        # 6 x 24 px: the bottom hidden by an occluder; the junction-to-top extent, not 10 m
        ([100.0, 50.0, 106.0, 74.0], 12.0, 12.0, "top", 5.0, 2e-4 + 1.0 / 12**2),
        # the bottom border cuts it: the junction-to-top extent
        ([100.0, 100.0, 130.0, 239.5], 50.0, 89.5, "top", 1.2, 2e-4 + 1.0 / 50**2),
        # the top border cuts it: the junction-to-bottom extent
        ([100.0, -0.5, 130.0, 200.0], 50.5, 150.0, "bottom", 1.2, 3e-4 + 1.5 / 150**2),
        # both: the width
        ([100.0, -0.5, 130.0, 239.5], 60.0, 180.0, "width", 1.0, 4e-4 + 2.0 / 30**2),
        # every border but the right: the smaller of the width's and the height's distances
        ([-0.5, -0.5, 12.0, 239.5], 60.0, 180.0, "width", 1.0, 4e-4 + 2.0 / 12.5**2),
    ],
)
def test_range_laws_and_branch_rule(
    box: list[float], top: float, bottom: float, branch: str, distance: float, rel_var: float
) -> None:
    e, b = extents(box, top, bottom)
    assert MODEL.branch(e, b, CAMERA) == branch
    got = MODEL.distance(e, b, CAMERA)
    assert got[0] == pytest.approx(distance)
    assert got[1] == pytest.approx(rel_var)
    assert got[2] == branch


def test_power_law_and_model_checks() -> None:
    assert PowerLaw(a=2.0, b=1.5)(4.0) == pytest.approx(0.25)
    with pytest.raises(ValueError, match="laws"):
        dataclasses.replace(MODEL, laws={"height": PowerLaw(a=1.0, b=1.0)})


def test_pole_extents_of_level_and_leaning_views() -> None:
    # level camera: the box is already upright, extents are pixel spans
    level = CameraState(position=np.array([0.0, 0.0, 0.5]), head_yaw=0.3, head_pitch=0.0)
    box = np.array([CAMERA.cx - 3.0, 70.0, CAMERA.cx + 3.0, 170.0])
    e = pole_extents(box, np.array([CAMERA.cx, 95.0]), CAMERA, level)
    assert (e.width, e.height, e.top, e.bottom) == pytest.approx((6.0, 100.0, 25.0, 75.0))
    # a pole off to the side of a camera pitched down leans in the image: its box, that of a
    # 0.1 m wide strip facing the camera from the ground to 0.8 m, is wider than the pole
    pitched = CameraState(position=np.array([0.0, 0.0, 0.5]), head_yaw=0.0, head_pitch=0.4)
    pole = np.array([2.0, -0.8])
    distance = float(np.hypot(*pole))
    side = 0.05 * np.array([-pole[1], pole[0]]) / distance
    corners = np.array(
        [[*(pole + s * side), z] for s in (-1.0, 1.0) for z in (0.0, 0.8)] + [[*pole, 0.6]]
    )
    uv, _ = project_points(
        (corners - pitched.position) @ pitched.rotation(),
        CAMERA.fx,
        CAMERA.fy,
        CAMERA.cx,
        CAMERA.cy,
    )
    box = np.concatenate([uv[:4].min(axis=0), uv[:4].max(axis=0)])
    expected_width = CAMERA.fx * 0.1 / distance
    assert box[2] - box[0] > 2 * expected_width  # it does lean
    e = pole_extents(box, uv[4], CAMERA, pitched)
    # the box's top and bottom rows are those of the strip's higher corners (the corners of a
    # horizontal edge sit on different rows in a pitched view): a little beyond the axis ends
    assert e.height == pytest.approx(CAMERA.fx * 0.8 / distance, rel=0.02)
    assert e.top == pytest.approx(CAMERA.fx * 0.2 / distance, rel=0.02)
    assert e.bottom == pytest.approx(CAMERA.fx * 0.6 / distance, rel=0.02)
    assert e.width == pytest.approx(expected_width, rel=0.05)


def test_model_round_trips_through_dict() -> None:
    assert PoleRangeModel.from_dict(dataclasses.asdict(MODEL)) == MODEL


@pytest.mark.parametrize("yaw", [-1.0, 0.0, 0.4])
@pytest.mark.parametrize("pitch", [-0.2, 0.0, 0.3])
def test_bearing_of_centred_box_is_head_yaw(yaw: float, pitch: float) -> None:
    state = CameraState(position=np.array([0.0, 0.0, 0.5]), head_yaw=yaw, head_pitch=pitch)
    centre = np.array([CAMERA.cx, CAMERA.cy])
    range_m, bearing = pole_range_bearing(centre, 3.0, CAMERA, state)
    assert bearing == pytest.approx(yaw, abs=1e-12)
    assert range_m == pytest.approx(3.0)


def test_range_bearing_from_camera_offset() -> None:
    # camera 6 cm ahead of the robot origin, looking 0.5 rad left: the pole axis lies 2 m along
    # the ray, so its range and bearing from the origin follow from the triangle
    state = CameraState(position=np.array([0.06, 0.0, 0.5]), head_yaw=0.5, head_pitch=0.1)
    range_m, bearing = pole_range_bearing(np.array([CAMERA.cx, 80.0]), 2.0, CAMERA, state)
    axis = np.array([0.06, 0.0]) + 2.0 * np.array([math.cos(0.5), math.sin(0.5)])
    assert range_m == pytest.approx(float(np.hypot(*axis)))
    assert bearing == pytest.approx(math.atan2(axis[1], axis[0]))


@pytest.fixture(scope="module")
def detector() -> CnnPoleDetector:
    return CnnPoleDetector(CnnDetectorConfig(), CAMERA, CODES, POLE)


def test_packaged_weights_forward_shapes(detector: CnnPoleDetector) -> None:
    data = torch.load(default_weights(), map_location="cpu", weights_only=True)
    assert default_weights().stat().st_size < 5e6
    net = load_network(data)
    with torch.inference_mode():
        out = net(torch.zeros(2, 3, CAMERA.height, CAMERA.width))
    assert out.shape == (2, len(detector.classes) + N_REGRESSION, *GRID)
    assert detector.classes[:6] == tuple(f"pole_{c.top}_{c.bottom}" for c in CODES)
    image = np.full((CAMERA.height, CAMERA.width, 3), 90, np.uint8)
    found = detector.detect_objects(image)
    assert all(isinstance(d, Detection) and d.box.shape == (4,) for d in found)
    state = CameraState(position=np.array([0.05, 0.0, 0.52]), head_yaw=0.0, head_pitch=0.0)
    assert detector.detect(image, state) == []  # a grey frame holds no pole


def test_observe_pole_gives_bearing_and_covariance(detector: CnnPoleDetector) -> None:
    state = CameraState(position=np.array([0.0, 0.0, 0.52]), head_yaw=0.3, head_pitch=0.1)
    box = np.array([CAMERA.cx - 4.0, CAMERA.cy - 30.0, CAMERA.cx + 4.0, CAMERA.cy + 30.0])
    keypoint = np.array([CAMERA.cx, CAMERA.cy - 15.0])
    pole = Detection(class_name="pole_pink_blue", class_id=2, box=box, score=0.9, keypoint=keypoint)
    obs = detector.observe_pole(2, pole, state)
    assert obs is not None and obs.landmark_id == 2 and obs.score == 0.9
    assert obs.bearing_rad == pytest.approx(0.3, abs=1e-9)
    distance, rel_var, _ = detector.range_model.distance(
        pole_extents(box, keypoint, CAMERA, state), box, CAMERA
    )
    assert obs.range_m == pytest.approx(distance)
    assert obs.cov[0, 0] == pytest.approx(rel_var * obs.range_m**2)
    assert obs.cov[1, 1] > 0 and obs.cov[0, 1] == 0
    thin = dataclasses.replace(pole, box=np.array([10.0, 10.0, 10.2, 50.0]))
    assert detector.observe_pole(2, thin, state) is None


def test_one_sighting_per_pole(detector: CnnPoleDetector) -> None:
    state = CameraState(position=np.array([0.0, 0.0, 0.52]), head_yaw=0.0, head_pitch=0.0)
    box = np.array([150.0, 80.0, 158.0, 140.0])
    keypoint = np.array([154.0, 95.0])

    def pole(class_id: int, score: float, shift: float = 0.0) -> Detection:
        return Detection(
            class_name=detector.classes[class_id],
            class_id=class_id,
            box=box + np.array([shift, 0.0, shift, 0.0]),
            score=score,
            keypoint=keypoint + np.array([shift, 0.0]),
        )

    found = detector.observations(
        [pole(1, 0.5), pole(4, 0.8), pole(4, 0.6, shift=60.0), pole(7, 0.9)], state
    )
    # pole 4 twice: the better; pole 1 on the same spot as pole 4: the same pole, dropped;
    # class 7 (the ball) is no pole
    assert [(o.landmark_id, o.score) for o in found] == [(4, 0.8)]


def test_fused_network_matches_unfused() -> None:
    torch.manual_seed(0)
    net = PoleNet(NetConfig())
    for module in net.modules():  # non-trivial batch-norm statistics
        if isinstance(module, torch.nn.BatchNorm2d):
            assert module.running_mean is not None and module.running_var is not None
            module.running_mean.uniform_(-0.5, 0.5)
            module.running_var.uniform_(0.5, 2.0)
    net.eval()
    x = torch.rand(1, 3, CAMERA.height, CAMERA.width)
    with torch.inference_mode():
        expected = net(x)
        fused = fuse_batch_norms(net)
        assert not any(isinstance(m, torch.nn.BatchNorm2d) for m in fused.modules())
        torch.testing.assert_close(fused(x), expected, atol=1e-4, rtol=1e-4)


@pytest.mark.parametrize(
    "image",
    [
        np.zeros((240, 320), np.uint8),
        np.zeros((240, 320, 3), np.float32),
        np.zeros((120, 160, 3), np.uint8),
        [[0, 0, 0]],
    ],
)
def test_bad_image_rejected(detector: CnnPoleDetector, image: object) -> None:
    state = CameraState(position=np.zeros(3), head_yaw=0.0, head_pitch=0.0)
    with pytest.raises(ValueError, match="image"):
        detector.detect(image, state)  # type: ignore[arg-type]


def test_bad_config_and_setup_rejected(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="score_threshold"):
        CnnDetectorConfig(score_threshold=1.5)
    with pytest.raises(ValueError, match="max_detections"):
        CnnDetectorConfig(max_detections=0)
    with pytest.raises(TypeError, match="weights"):
        CnnDetectorConfig(weights="pole_detector.pt")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="camera"):
        CnnPoleDetector(CnnDetectorConfig(), CameraModel(width=640, height=480), CODES, POLE)
    with pytest.raises(ValueError, match="codes"):
        CnnPoleDetector(CnnDetectorConfig(), CAMERA, (*CODES, CODES[0]), POLE)
    data = torch.load(default_weights(), map_location="cpu", weights_only=True)
    data["classes"] = ["pole_pink_purple", *data["classes"][1:]]
    renamed = tmp_path / "renamed.pt"
    torch.save(data, renamed)
    with pytest.raises(ValueError, match="pole_pink_yellow"):
        CnnPoleDetector(CnnDetectorConfig(weights=renamed), CAMERA, CODES, POLE)
    bogus = tmp_path / "bogus.pt"
    torch.save({"state_dict": {}}, bogus)
    with pytest.raises(ValueError, match="weights file"):
        CnnPoleDetector(CnnDetectorConfig(weights=bogus), CAMERA, CODES, POLE)


def test_train_config_checks_the_network_shape() -> None:
    assert TrainConfig(channels=(8, 16, 24, 32), head_channels=16).channels == (8, 16, 24, 32)
    with pytest.raises(ValueError, match="channels"):
        TrainConfig(channels=(8, 16, 0, 32))
    with pytest.raises(ValueError, match="head_channels"):
        TrainConfig(head_channels=-1)
    with pytest.raises(ValueError, match="epochs"):
        TrainConfig(epochs=0)


def test_weights_are_saved_whole_or_not_at_all(tmp_path: Path) -> None:
    """A save that fails (here: something that does not pickle) leaves the file of an earlier
    save as it was, and nothing beside it."""
    path = tmp_path / "weights.pt"
    save(path, {"format": 1})
    before = path.read_bytes()
    with pytest.raises(Exception, match="pickle"):
        save(path, {"format": 2, "bad": lambda: None})
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["weights.pt"]


def test_a_flipped_view_is_read_as_its_copy(detector: CnnPoleDetector) -> None:
    """A negative-stride image (a view flipped left to right) is what its copy is; torch takes
    no negative strides."""
    image = np.random.default_rng(0).integers(0, 255, (CAMERA.height, CAMERA.width, 3), np.uint8)
    flipped = image[:, ::-1]
    copied = np.ascontiguousarray(flipped)
    assert [d.box.tolist() for d in detector.detect_objects(flipped)] == [
        d.box.tolist() for d in detector.detect_objects(copied)
    ]


@pytest.mark.parametrize("factor", [2, 3, 7])
def test_downscaled_detections_map_the_shrunk_image_onto_the_whole_frame(
    detector: CnnPoleDetector, factor: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A box over the whole shrunk image (pixel edges -1/2 to size - 1/2) comes back over the
    whole frame, and the shrunk image's first pixel centre at the centre of the frame's pixels
    it averaged, whether or not ``factor`` divides the frame's size (320 x 240: 7 does not)."""
    width, height = CAMERA.width // factor, CAMERA.height // factor

    def one_box(*_: object) -> Decoded:
        return Decoded(
            class_ids=np.array([0]),
            scores=np.array([0.9], np.float32),
            keypoints=np.array([[0.0, 0.0]], np.float32),
            boxes=np.array([[-0.5, -0.5, width - 0.5, height - 0.5]], np.float32),
        )

    monkeypatch.setattr(cnn_model, "decode", one_box)
    image = np.zeros((CAMERA.height, CAMERA.width, 3), np.uint8)
    (found,) = detector.detect_objects_downscaled(image, factor)
    np.testing.assert_allclose(found.box, [-0.5, -0.5, CAMERA.width - 0.5, CAMERA.height - 0.5])
    area = np.array([CAMERA.width / width, CAMERA.height / height])  # frame pixels per pixel
    np.testing.assert_allclose(found.keypoint, (area - 1) / 2)
