"""MP4 videos round-trip through OpenCV; learning curves from hand-written SB3 monitor files."""

from __future__ import annotations

import json
import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from agents.learning_curves import moving_mean, parse_baselines, plot, read_monitor
from agents.video import write_video

HEIGHT, WIDTH = 48, 64


def _frame(rgb: tuple[int, int, int]) -> np.ndarray:
    return np.tile(np.array(rgb, np.uint8), (HEIGHT, WIDTH, 1))


def test_video_round_trips_through_opencv(tmp_path: Path) -> None:
    colours = [(255, 0, 0)] * 4 + [(0, 0, 255)] * 3  # pure red, then pure blue (RGB)
    path = write_video([_frame(c) for c in colours], tmp_path / "sub" / "clip.mp4", fps=10.0)
    assert path == tmp_path / "sub" / "clip.mp4" and path.stat().st_size > 0
    capture = cv2.VideoCapture(str(path))
    decoded = []
    while True:
        ok, bgr = capture.read()
        if not ok:
            break
        decoded.append(bgr)
    fps = capture.get(cv2.CAP_PROP_FPS)
    capture.release()
    assert len(decoded) == 7
    assert fps == pytest.approx(10.0)
    for bgr, rgb in zip(decoded, colours, strict=True):
        assert bgr.shape == (HEIGHT, WIDTH, 3)
        mean_bgr = bgr.reshape(-1, 3).mean(axis=0)
        np.testing.assert_allclose(mean_bgr, rgb[::-1], atol=10.0)


def test_video_accepts_an_upper_case_suffix(tmp_path: Path) -> None:
    assert write_video([_frame((0, 255, 0))], tmp_path / "a.MP4", fps=5.0).is_file()


@pytest.mark.parametrize(
    "name, fps, frames, argument",
    [
        ("clip.avi", 10.0, [_frame((1, 2, 3))], "path"),
        ("clip", 10.0, [_frame((1, 2, 3))], "path"),
        ("clip.mp4", 0.0, [_frame((1, 2, 3))], "fps"),
        ("clip.mp4", math.nan, [_frame((1, 2, 3))], "fps"),
        ("clip.mp4", math.inf, [_frame((1, 2, 3))], "fps"),
        ("clip.mp4", -5.0, [_frame((1, 2, 3))], "fps"),
        ("clip.mp4", 10.0, [], "frames"),
        (
            "clip.mp4",
            10.0,
            [_frame((1, 2, 3)), np.zeros((HEIGHT, WIDTH + 2, 3), np.uint8)],
            "frames",
        ),
        ("clip.mp4", 10.0, [_frame((1, 2, 3)), np.zeros((HEIGHT, WIDTH, 3), np.float32)], "frames"),
        ("clip.mp4", 10.0, [np.zeros((HEIGHT, WIDTH, 3), np.float32)], "frames"),
        ("clip.mp4", 10.0, [np.zeros((HEIGHT, WIDTH), np.uint8)], "frames"),
    ],
)
def test_video_refuses_bad_input(
    tmp_path: Path, name: str, fps: float, frames: list[np.ndarray], argument: str
) -> None:
    with pytest.raises(ValueError, match=argument):
        write_video(frames, tmp_path / name, fps=fps)


def test_moving_mean_by_hand() -> None:
    values = np.array([1.0, 2.0, 3.0, 4.0])
    np.testing.assert_allclose(moving_mean(values, 2), [1.0, 1.5, 2.5, 3.5])
    np.testing.assert_allclose(moving_mean(values, 1), values)
    np.testing.assert_allclose(moving_mean(values, 10), [1.0, 1.5, 2.0, 2.5])
    with pytest.raises(ValueError, match="window"):
        moving_mean(values, 0)


def _write_monitor(path: Path, rows: list[tuple[float, int, float]], t_start: float = 0.0) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    header = json.dumps({"t_start": t_start, "env_id": "x"})
    lines = ["#" + header, "r,l,t"]
    lines += [f"{r},{length},{t}" for r, length, t in rows]
    path.write_text("\n".join(lines) + "\n")


def _run(root: Path, name: str) -> Path:
    run = root / name
    _write_monitor(run / "monitor" / "0.monitor.csv", [(1.5, 100, 2.0), (2.5, 50, 5.0)])
    _write_monitor(run / "monitor" / "1.monitor.csv", [(-1.0, 80, 3.0), (4.0, 20, 6.5)])
    return run


def test_read_monitor_merges_envs_by_end_time(tmp_path: Path) -> None:
    steps, returns = read_monitor(_run(tmp_path, "run"))
    # end times 2.0, 3.0, 5.0, 6.5: lengths 100, 80, 50, 20
    np.testing.assert_allclose(steps, [100, 180, 230, 250])
    np.testing.assert_allclose(returns, [1.5, -1.0, 2.5, 4.0])


def test_read_monitor_orders_by_each_envs_own_start(tmp_path: Path) -> None:
    run = tmp_path / "run"
    _write_monitor(run / "monitor" / "0.monitor.csv", [(1.0, 10, 5.0)], t_start=100.0)
    _write_monitor(run / "monitor" / "1.monitor.csv", [(2.0, 20, 1.0)], t_start=110.0)
    steps, returns = read_monitor(run)  # ends at 105 and 111 s: env 0's episode first
    np.testing.assert_allclose(steps, [10, 30])
    np.testing.assert_allclose(returns, [1.0, 2.0])


def test_read_monitor_needs_monitor_files(tmp_path: Path) -> None:
    (tmp_path / "empty" / "monitor").mkdir(parents=True)
    with pytest.raises(ValueError, match="monitor"):
        read_monitor(tmp_path / "empty")
    _write_monitor(tmp_path / "unfinished" / "monitor" / "0.monitor.csv", [])
    with pytest.raises(ValueError, match="no finished episode"):
        read_monitor(tmp_path / "unfinished")


def test_plot_writes_a_700_by_400_png(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    out = tmp_path / "plots" / "curves.png"
    runs = [_run(tmp_path, "seed0"), _run(tmp_path, "seed1")]
    assert plot(runs, out, "title", 2, {"scan": 1.0}) == out
    image = cv2.imread(str(out))
    assert image is not None and image.shape[:2] == (400, 700)
    # the baseline's dashed grey line: a row of grey pixels across the plot
    grey = np.all(np.abs(image.astype(int) - 128) <= 10, axis=2)
    assert grey.sum(axis=1).max() > 100


def test_parse_baselines() -> None:
    assert parse_baselines(["scan=1.5", "fixed=-2"]) == {"scan": 1.5, "fixed": -2.0}
    assert parse_baselines([]) == {}
    with pytest.raises(ValueError, match="NAME=VALUE"):
        parse_baselines(["abc"])
