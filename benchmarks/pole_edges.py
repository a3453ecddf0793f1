"""Range from the pole's band edges against range from the CNN box extents, on held-out frames.

For every labelled pole the shipped CNN detects (``training.train_detector``'s matching: a
detection of its class near its band junction), the range from the box extents
(:class:`perception.vision.cnn_detector.PoleRangeModel`) and, where the three band edges are
found, from the edges (:mod:`perception.vision.pole_edges`), all against the label's true
range. Per true-range bucket: how often the edges are found, the mean and median absolute
relative range error of each, and of what the detector reports (edges, else a near pole's
width, else the extents; ``detector_dropped``: the fraction of near, cut poles it refuses to
measure). The class colour check is off here: every matched detection is of the right class.
Fits the edge rows' noise ``row_std_px`` (robust: the median of the squared errors normalised
by the fit's relative variance at 1 px, over the median of chi-square with one degree of
freedom) and reports the mean normalised squared error (NEES, 1 = consistent) of the edge
ranges at that noise.

Usage (the dataset from ``python -m spl_env.datasets --out data/poles_val --images 1000
--seed 1``)::

    python -m benchmarks.pole_edges --data data/poles_val

Writes ``--out`` (default ``benchmarks/results/pole_edges.json``).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import torch
from scipy import stats

from perception.types import CameraModel, PoleCode, PoleGeometry
from perception.vision import CnnDetectorConfig, CnnPoleDetector
from perception.vision.cnn_detector import vertical_lean
from perception.vision.pole_edges import PoleEdgeConfig, pole_edge_distance
from training.train_detector import load_dataset, match_sightings

RESULTS = Path("benchmarks/results")
BUCKETS_M = ((0.0, 1.5), (1.5, 3.0), (3.0, 5.0), (5.0, 10.0))
GROSS = 0.25  # relative errors this large are outliers, left out of the noise fit


def measure(data: Path) -> list[dict[str, Any]]:
    """Per matched pole: true range, extent range, edge range (NaN if no fit) and, for edge
    fits, the relative variance at 1 px of row noise."""
    images, records, meta = load_dataset(data)
    camera = CameraModel(**meta["camera"])
    codes = [PoleCode(**code) for code in meta["pole_codes"]]
    pole = PoleGeometry()
    extents_only = CnnDetectorConfig(edges=None, check_colours=False)
    detector = CnnPoleDetector(extents_only, camera, codes, pole)
    full = CnnPoleDetector(CnnDetectorConfig(check_colours=False), camera, codes, pole)
    edges = PoleEdgeConfig()
    image_of = {id(o): k for k, r in enumerate(records) for o in r["objects"]}
    rows = []
    for s in match_sightings(detector, images, records):
        obs = detector.observe_pole(s.obj["landmark_id"], s.detection, s.state)
        if obs is None:
            continue
        rotation = s.state.rotation()
        fit = pole_edge_distance(
            images[image_of[id(s.obj)]],
            s.detection.box,
            s.detection.keypoint,
            vertical_lean(s.detection.box, camera, rotation),
            camera,
            rotation,
            float(s.state.position[2]),
            pole,
            edges,
        )
        edge_range, unit_var = math.nan, math.nan
        if fit is not None:
            # the same ray as the extent sighting, at the edge distance: scale the range
            camera_xy = s.state.position[:2]
            heading = np.array([math.cos(obs.bearing_rad), math.sin(obs.bearing_rad)])
            axis = obs.range_m * heading
            direction = (axis - camera_xy) / np.linalg.norm(axis - camera_xy)
            edge_range = float(np.linalg.norm(camera_xy + fit.distance_m * direction))
            unit_var = fit.relative_variance(1.0, camera.fx)
        chosen = full.observe_pole(
            s.obj["landmark_id"], s.detection, s.state, images[image_of[id(s.obj)]]
        )
        rows.append(
            {
                "true_range_m": float(s.obj["range_m"]),
                "extent_range_m": float(obs.range_m),
                "edge_range_m": edge_range,
                "edge_unit_rel_var": unit_var,
                "detector_range_m": math.nan if chosen is None else float(chosen.range_m),
            }
        )
    return rows


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Fit rate and errors per bucket, the fitted ``row_std_px`` and the edge ranges' NEES."""
    true = np.array([r["true_range_m"] for r in rows])
    extent = np.array([r["extent_range_m"] for r in rows]) / true - 1.0
    edge = np.array([r["edge_range_m"] for r in rows]) / true - 1.0
    unit_var = np.array([r["edge_unit_rel_var"] for r in rows])
    detector = np.array([r["detector_range_m"] for r in rows]) / true - 1.0
    found = np.isfinite(edge)
    kept = np.isfinite(detector)
    clean = found & (np.abs(edge) < GROSS)
    median_chi2 = float(stats.chi2.median(1))
    row_std = math.sqrt(float(np.median(edge[clean] ** 2 / unit_var[clean])) / median_chi2)
    nees = edge[clean] ** 2 / (row_std**2 * unit_var[clean])

    def errors(rel: np.ndarray) -> dict[str, float]:
        return {
            "mean_abs_rel": float(np.mean(np.abs(rel))) if len(rel) else math.nan,
            "median_abs_rel": float(np.median(np.abs(rel))) if len(rel) else math.nan,
            "mean_rel": float(np.mean(rel)) if len(rel) else math.nan,
            "gross_fraction": float(np.mean(np.abs(rel) >= GROSS)) if len(rel) else math.nan,
        }

    buckets = {}
    for lo, hi in BUCKETS_M:
        m = (true >= lo) & (true < hi)
        buckets[f"{lo:g}-{hi:g} m"] = {
            "poles": int(m.sum()),
            "edges_found": float(found[m].mean()) if m.any() else math.nan,
            "extent": errors(extent[m]),
            "edges_where_found": errors(edge[m & found]),
            "extent_where_edges_found": errors(extent[m & found]),
            "detector_dropped": float(np.mean(~kept[m])) if m.any() else math.nan,
            "detector": errors(detector[m & kept]),
        }
    return {
        "poles": len(rows),
        "edges_found": float(found.mean()),
        "extent": errors(extent),
        "edges_where_found": errors(edge[found]),
        "extent_where_edges_found": errors(extent[found]),
        "detector_dropped": float(np.mean(~kept)),
        "detector": errors(detector[kept]),
        "by_true_range": buckets,
        "row_std_px_fitted": row_std,
        "row_std_px_configured": PoleEdgeConfig().row_std_px,
        "edge_nees_at_fitted": float(np.mean(nees)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=Path("data/poles_val"))
    parser.add_argument("--out", type=Path, default=RESULTS / "pole_edges.json")
    args = parser.parse_args()
    torch.set_num_threads(1)
    summary = {"dataset": str(args.data), **summarise(measure(args.data))}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
