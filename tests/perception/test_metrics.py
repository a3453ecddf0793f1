"""Estimation metrics against hand-computed values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.metrics import landmark_errors, landmark_range_bearing, pose_nees, position_error


def test_position_error_is_planar_distance() -> None:
    assert position_error([1.0, 2.0, 3.0], [4.0, 6.0, -1.0]) == pytest.approx(5.0)


def test_pose_nees_closed_form_with_wrapped_heading() -> None:
    cov = np.diag([0.04, 0.01, 0.25])
    # errors 0.2 m, -0.1 m and a heading 0.1 rad across the ±pi seam
    nees = pose_nees([1.2, 0.9, math.pi - 0.05], [1.0, 1.0, -math.pi + 0.05], cov)
    assert nees == pytest.approx(0.2**2 / 0.04 + 0.1**2 / 0.01 + 0.1**2 / 0.25)


def test_landmark_errors_match_by_id_and_skip_unknown_ids() -> None:
    errors = landmark_errors(
        [3, 5], [[0.0, 0.0], [2.0, 2.0]], [5, 9, 3], [[2.0, 2.5], [0.0, 0.0], [0.3, 0.4]]
    )
    np.testing.assert_allclose(errors, [0.5, 0.5])


def test_landmark_range_bearing_keyed_by_id() -> None:
    truth = landmark_range_bearing([1.0, 1.0, math.pi / 2], [7, 2], [[1.0, 3.0], [0.0, 1.0]])
    assert set(truth) == {7, 2}
    np.testing.assert_allclose(truth[7], [2.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(truth[2], [1.0, math.pi / 2], atol=1e-12)
