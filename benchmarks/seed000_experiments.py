"""Seed 000's experiments reproduced in simulation: Tables 4.1, 4.2, 4.3 and filter consistency.

    python benchmarks/seed000_experiments.py                      # everything (~40 min, 2 cores)
    python benchmarks/seed000_experiments.py --only table43 nees  # a part

Writes ``benchmarks/results/seed000/``: ``results.json``, ``tables.md`` (the seed's table
layouts) and PNG plots (maps with the true and estimated paths and landmarks, errors over time,
average NEES against its 95 % chi-square band).

- **Table 4.1** (back ends): ten-minute walks among the poles (random waypoints, head scan,
  randomised lighting), every back end on the same recorded sightings of each front end.
- **Table 4.2** (front ends): both front ends on 150 random frames from a walking robot under
  randomised lighting (``benchmarks/front_ends.py --protocol walking``); the per-image
  predictions go to ``table42_predictions.json``.
- **Table 4.3** (front end x back end): seed 000's one-minute square walk, odometry alone beside.
- **Consistency**: Monte Carlo runs of the classic and the FEJ filter, (a) in a synthetic world
  whose noise is exactly the filter's model (Huang et al. 2008's study), (b) in the simulator
  (geometric camera mode, the walk odometry's systematic errors included). Average pose NEES
  over time against the 95 % band of its chi-square distribution.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from pathlib import Path
from typing import Any

import cv2
import gymnasium as gym
import numpy as np
from scipy.stats import chi2

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import load_policy, summarise
from agents.recording import frontends_for, record_episode
from perception.replay import ReplayResult, SightingLog, replay
from perception.slam import EkfSlamConfig
from perception.synthetic import CircleWorld, circle_run
from perception.vision.cnn_detector import CnnDetectorConfig
from spl_env.config import EnvConfig
from spl_env.envs.core import SplEnv
from spl_env.rendering import TopDownView

OUT = Path("benchmarks/results/seed000")
FRONTENDS = ("colour", "cnn")
# back-end variants: the seed's Table 4.1 / 4.3 rows plus the Mahalanobis gate and combinations
VARIANTS: dict[str, dict[str, Any]] = {
    "classic": {"backend": "classic"},
    "gated (0.4 m, pi/3)": {"backend": "gated"},
    "gated (Mahalanobis)": {"backend": "classic", "gate": "mahalanobis"},
    "minimal view n=3": {"backend": "minimal_view", "min_views": 3},
    "minimal view n=5": {"backend": "minimal_view", "min_views": 5},
    "FEJ": {"backend": "fej"},
    "FEJ, minimal view n=3": {"backend": "fej", "min_views": 3},
    "FEJ, minimal view n=5, gated": {"backend": "fej", "min_views": 5, "gate": "thresholds"},
    "FEJ, minimal view n=3, Mahalanobis": {"backend": "fej", "min_views": 3, "gate": "mahalanobis"},
}
SEED_TABLE_41 = {  # landmark mean, landmark std, robot mean, robot std (m), Gutmann dataset
    "classic EKF SLAM": (0.2990, 0.05240, 0.1486, 0.04544),
    "filter EKF SLAM": (0.1870, 0.04787, 0.2451, 0.4142),
    "minimal view EKF SLAM, n=5": (0.2755, 0.05088, 0.1458, 0.08423),
    "minimal view EKF SLAM, n=3": (0.1369, 0.04122, 0.09702, 0.03284),
    "FEJ-EKF SLAM": (0.1662, 0.07848, 0.1072, 0.05832),
}
SEED_TABLE_43_BEST = {"robot_mean_m": 0.17, "landmark_mean_m": 0.21, "odometry_mean_m": 0.5039}


def record(
    behaviour: str, episode_s: float, episodes: int, seed: int, frontends: tuple[str, ...]
) -> tuple[list[SightingLog], EnvConfig]:
    """Episodes of the head-scan policy with every front end's sightings recorded."""
    env = gym.make(
        "SPL/ActiveVision-v0",
        body_behaviour=behaviour,
        episode_s=episode_s,
        randomise_lighting=True,
        frontend="colour",
    )
    config = env.get_wrapper_attr("config")
    policy = load_policy("scan", config)
    fronts = frontends_for(env, frontends)
    logs = []
    for k in range(episodes):
        t0 = time.perf_counter()
        logs.append(record_episode(env, policy, seed + k, fronts))
        print(f"  recorded {behaviour} episode {k} ({time.perf_counter() - t0:.0f} s)", flush=True)
    env.close()
    return logs, config


def compare_back_ends(
    logs: list[SightingLog], frontends: tuple[str, ...], base: EkfSlamConfig
) -> tuple[list[dict[str, Any]], dict[tuple[str, str], list[ReplayResult]]]:
    """Every variant on every front end's sightings of every log: rows of mean summaries."""
    rows, results = [], {}
    for frontend in frontends:
        for name, fields in VARIANTS.items():
            config = dataclasses.replace(base, **fields)
            runs = [replay(log, frontend, config) for log in logs]
            results[(frontend, name)] = runs
            rows.append(
                {
                    "frontend": frontend,
                    "backend": name,
                    "config": fields,
                    "mean": summarise([r.summary() for r in runs]),  # type: ignore[misc]
                    "episodes": [r.summary() for r in runs],
                }
            )
            print(f"  {frontend:6s} {name:36s} {_short(rows[-1]['mean'])}", flush=True)
    return rows, results


def _short(mean: dict[str, Any]) -> str:
    keys = ("mean_position_error_m", "mean_landmark_error_m", "mean_pose_nees")
    return " ".join(f"{k.split('_')[1]}={_fmt(mean[k])}" for k in keys)


def _fmt(value: float | None, digits: int = 3) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def table_41_markdown(rows: list[dict[str, Any]], episodes: int, minutes: float) -> str:
    """Seed Table 4.1 layout, one block per front end, with the seed's numbers below."""
    lines = [
        f"### Table 4.1 analogue: back ends, {episodes} x {minutes:.0f}-minute walks among the "
        "poles (head scan, randomised lighting)",
        "",
        "| front end | back end | landmark mean (m) | landmark std (m) | robot mean (m) | "
        "robot std (m) | pose NEES | rejected |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        m = row["mean"]
        lines.append(
            f"| {row['frontend']} | {row['backend']} | {_fmt(m['mean_landmark_error_m'])} | "
            f"{_fmt(m['std_landmark_error_m'])} | {_fmt(m['mean_position_error_m'])} | "
            f"{_fmt(m['std_position_error_m'])} | {_fmt(m['mean_pose_nees'], 1)} | "
            f"{_fmt(m['rejected_sightings'], 0)} |"
        )
    lines += ["", "Seed 000 Table 4.1 (Gutmann dataset, 10 minutes):", ""]
    lines += [
        "| back end | landmark mean | landmark std | robot mean | robot std |",
        "|---|---|---|---|---|",
    ]
    lines += [
        f"| {k} | " + " | ".join(f"{v:.4g}" for v in vals) + " |"
        for k, vals in SEED_TABLE_41.items()
    ]
    return "\n".join(lines)


def table_43_markdown(rows: list[dict[str, Any]], episodes: int) -> str:
    """Seed Table 4.3 layout: back ends down, front ends across, odometry alone on top."""
    by = {(r["frontend"], r["backend"]): r["mean"] for r in rows}
    fronts = sorted({r["frontend"] for r in rows}, key=FRONTENDS.index)
    odometry = np.mean([by[(f, "classic")]["mean_odometry_error_m"] for f in fronts])
    header = " | ".join(f"{f}: robot mean | {f}: landmark mean" for f in fronts)
    lines = [
        f"### Table 4.3 analogue: one-minute square walk, {episodes} episodes (head scan, "
        "randomised lighting); mean errors (m)",
        "",
        f"Odometry alone: robot mean {odometry:.3f} m (seed 000: 0.504 m).",
        "",
        f"| back end | {header} |",
        "|---|" + "---|---|" * len(fronts),
    ]
    for name in VARIANTS:
        cells = " | ".join(
            f"{_fmt(by[(f, name)]['mean_position_error_m'])} | "
            f"{_fmt(by[(f, name)]['mean_landmark_error_m'])}"
            for f in fronts
        )
        lines.append(f"| {name} | {cells} |")
    lines += [
        "",
        "Seed 000 best: robot 0.17 m (YOLOv8s, minimal view FEJ n=5), landmark 0.21 m "
        "(YOLOv8m, minimal view FEJ n=5), odometry alone 0.50 m.",
    ]
    return "\n".join(lines)


def map_plot(dims: Any, log: SightingLog, runs: dict[str, ReplayResult]) -> np.ndarray:
    """(H, W, 3) BGR top-down map: true path and landmarks (white), each run's path and map."""
    view = TopDownView(dims)
    img = view.background.copy()
    colours = [(0, 0, 255), (255, 128, 0), (0, 200, 255), (255, 0, 255)]
    for xy in log.landmarks:
        cv2.circle(img, view.px(xy), 7, (255, 255, 255), 2)
    true_pts = np.array([view.px(p) for p in log.true_poses], dtype=np.int32)
    cv2.polylines(img, [true_pts], False, (255, 255, 255), 2)
    for k, run in enumerate(runs.values()):
        colour = colours[k % len(colours)]
        pts = np.array([view.px(p) for p in run.poses], dtype=np.int32)
        cv2.polylines(img, [pts], False, colour, 1)
        for xy in run.final_landmarks:
            cv2.drawMarker(img, view.px(xy), colour, cv2.MARKER_CROSS, 12, 2)
    labels = [*((name, colours[k % len(colours)]) for k, name in enumerate(runs))]
    labels.append(("truth", (255, 255, 255)))
    bottom = img.shape[0] - 8
    for k, (name, colour) in enumerate(reversed(labels)):
        cv2.putText(img, name, (40, bottom - 16 * k), cv2.FONT_HERSHEY_SIMPLEX, 0.45, colour, 1)
    return img


def series_plot(
    times: np.ndarray,
    series: dict[str, np.ndarray],
    title: str,
    band: tuple[float, float] | None = None,
    y_max: float | None = None,
) -> np.ndarray:
    """(H, W, 3) BGR line plot of ``series`` over ``times`` (s), an optional shaded band."""
    width, height, margin = 800, 360, 50
    values = np.concatenate([s[np.isfinite(s)] for s in series.values()])
    top = y_max if y_max is not None else float(np.max(values)) * 1.05 if len(values) else 1.0
    if band is not None:
        top = max(top, band[1] * 1.2)
    img = np.full((height, width, 3), 255, np.uint8)

    def px(t: float, y: float) -> tuple[int, int]:
        u = margin + (t - times[0]) / max(times[-1] - times[0], 1e-9) * (width - 2 * margin)
        v = height - margin - min(y, top) / top * (height - 2 * margin)
        return int(u), int(v)

    if band is not None:
        cv2.rectangle(img, px(times[0], band[1]), px(times[-1], band[0]), (200, 235, 200), -1)
    cv2.line(img, px(times[0], 0), px(times[-1], 0), (0, 0, 0), 1)
    cv2.line(img, px(times[0], 0), px(times[0], top), (0, 0, 0), 1)
    for frac in (0.5, 1.0):
        cv2.putText(
            img,
            f"{top * frac:.2f}",
            (2, px(times[0], top * frac)[1] + 4),
            cv2.FONT_HERSHEY_SIMPLEX,
            0.4,
            (0, 0, 0),
            1,
        )
    cv2.putText(
        img,
        f"{times[-1]:.0f} s",
        (width - margin - 20, height - margin + 20),
        cv2.FONT_HERSHEY_SIMPLEX,
        0.4,
        (0, 0, 0),
        1,
    )
    colours = [(0, 0, 220), (220, 120, 0), (0, 160, 0), (160, 0, 160), (0, 140, 220)]
    for k, (name, s) in enumerate(series.items()):
        colour = colours[k % len(colours)]
        ok = np.isfinite(s)
        pts = np.array([px(t, y) for t, y in zip(times[ok], s[ok], strict=True)], np.int32)
        if len(pts) > 1:
            cv2.polylines(img, [pts], False, colour, 1)
        cv2.putText(
            img, name, (margin + 10, 20 + 16 * k), cv2.FONT_HERSHEY_SIMPLEX, 0.45, colour, 1
        )
    cv2.putText(img, title, (margin, height - 10), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1)
    return img


def back_end_experiment(
    name: str,
    behaviour: str,
    episode_s: float,
    episodes: int,
    seed: int,
    frontends: tuple[str, ...],
    out: Path,
) -> dict[str, Any]:
    """Record, replay every variant, plot the first episode; the JSON block of one table."""
    print(f"{name}: recording {episodes} x {episode_s:.0f} s ({behaviour})", flush=True)
    logs, config = record(behaviour, episode_s, episodes, seed, frontends)
    rows, results = compare_back_ends(logs, frontends, config.perception.slam)
    dims = config.scene.dimensions
    for frontend in frontends:
        shown = {v: results[(frontend, v)][0] for v in ("classic", "FEJ", _best(rows, frontend))}
        cv2.imwrite(str(out / f"{name}_{frontend}_map.png"), map_plot(dims, logs[0], shown))
        series = {"odometry": shown["classic"].odometry_errors_m}
        series |= {v: r.position_errors_m for v, r in shown.items()}
        cv2.imwrite(
            str(out / f"{name}_{frontend}_robot_error.png"),
            series_plot(logs[0].times_s, series, f"{name} {frontend}: robot position error (m)"),
        )
        cv2.imwrite(
            str(out / f"{name}_{frontend}_landmark_error.png"),
            series_plot(
                logs[0].times_s,
                {v: r.landmark_errors_m for v, r in shown.items()},
                f"{name} {frontend}: mean landmark error (m)",
            ),
        )
    return {
        "behaviour": behaviour,
        "episode_s": episode_s,
        "episodes": episodes,
        "seed": seed,
        "rows": rows,
    }


def _best(rows: list[dict[str, Any]], frontend: str) -> str:
    """The variant with the smallest sum of mean robot and landmark errors on ``frontend``."""

    def cost(row: dict[str, Any]) -> float:
        m = row["mean"]
        return m["mean_position_error_m"] + (m["mean_landmark_error_m"] or math.inf)

    return min((r for r in rows if r["frontend"] == frontend), key=cost)["backend"]


def consistency(runs: int, seed: int, out: Path) -> dict[str, Any]:
    """Monte Carlo average pose NEES of classic and FEJ: synthetic world and simulator."""
    band = (chi2.ppf(0.025, 3 * runs) / runs, chi2.ppf(0.975, 3 * runs) / runs)
    base = EkfSlamConfig()
    variants = {
        "classic": dataclasses.replace(base, backend="classic"),
        "FEJ": dataclasses.replace(base, backend="fej"),
    }
    report: dict[str, Any] = {"runs": runs, "band_95": band}
    # (a) synthetic: the filter's own noise model, the SPL poles as landmarks
    env = gym.make("SPL/ActiveVision-v0", camera_mode="geometric", frontend="colour")
    core = env.unwrapped
    if not isinstance(core, SplEnv):
        raise TypeError(f"consistency needs an SplEnv, got {type(core).__name__}")
    ids, landmarks = core.scene.landmark_ids.copy(), core.scene.landmarks.copy()
    env.close()
    world = CircleWorld()
    print(f"consistency: {runs} synthetic runs of {world.steps} steps", flush=True)
    logs = [
        circle_run(world, base, ids, landmarks, np.random.default_rng(seed + k))
        for k in range(runs)
    ]
    report["synthetic"] = _nees_block(logs, "synthetic", variants, band, out, "synthetic")
    # (b) simulator: geometric camera, three-minute square walks (walk odometry as it is)
    print(f"consistency: {runs} simulated 3-minute square walks (geometric camera)", flush=True)
    env = gym.make(
        "SPL/ActiveVision-v0",
        camera_mode="geometric",
        frontend="colour",
        body_behaviour="square",
        episode_s=180.0,
    )
    policy = load_policy("scan", env.get_wrapper_attr("config"))
    fronts = frontends_for(env, ("colour",))
    sim_logs = [record_episode(env, policy, seed + k, fronts) for k in range(runs)]
    env.close()
    report["simulator"] = _nees_block(sim_logs, "colour", variants, band, out, "simulator")
    return report


def _nees_block(
    logs: list[SightingLog],
    frontend: str,
    variants: dict[str, EkfSlamConfig],
    band: tuple[float, float],
    out: Path,
    name: str,
) -> dict[str, Any]:
    """Average NEES over the runs at each step for each variant, its plot and summary."""
    averages = {}
    block: dict[str, Any] = {}
    for label, config in variants.items():
        results = [replay(log, frontend, config) for log in logs]
        nees = np.mean([r.pose_nees for r in results], axis=0)
        averages[label] = nees
        inside = (nees >= band[0]) & (nees <= band[1])
        block[label] = {
            "final_average_nees": float(nees[-1]),
            "mean_average_nees": float(np.mean(nees)),
            "last_tenth_average_nees": float(np.mean(nees[-len(nees) // 10 :])),
            "fraction_of_time_inside_band": float(np.mean(inside)),
            "ends_inside_band": bool(band[0] <= nees[-1] <= band[1]),
            "rms_position_error_m": float(
                np.sqrt(np.mean([np.mean(r.position_errors_m**2) for r in results]))
            ),
        }
        print(f"  {name} {label}: {json.dumps(block[label])}", flush=True)
    cv2.imwrite(
        str(out / f"nees_{name}.png"),
        series_plot(
            logs[0].times_s,
            averages,
            f"{name}: average pose NEES, 95 % band shaded",
            band=band,
            y_max=2 * band[1],
        ),
    )
    return block


def nees_markdown(report: dict[str, Any]) -> str:
    band = report["band_95"]
    lines = [
        f"### Consistency: average pose NEES over {report['runs']} Monte Carlo runs "
        f"(95 % band {band[0]:.2f}-{band[1]:.2f}; 3 = consistent)",
        "",
        "| world | filter | NEES at the end | mean over the last tenth | time inside band | "
        "RMS position error (m) |",
        "|---|---|---|---|---|---|",
    ]
    for world in ("synthetic", "simulator"):
        for label, b in report[world].items():
            lines.append(
                f"| {world} | {label} | {b['final_average_nees']:.2f} | "
                f"{b['last_tenth_average_nees']:.2f} | "
                f"{100 * b['fraction_of_time_inside_band']:.0f} % | "
                f"{b['rms_position_error_m']:.3f} |"
            )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--only",
        nargs="+",
        default=["table41", "table42", "table43", "nees"],
        choices=["table41", "table42", "table43", "nees"],
    )
    parser.add_argument("--table41-episodes", type=int, default=3)
    parser.add_argument("--table41-minutes", type=float, default=10.0)
    parser.add_argument("--table42-episodes", type=int, default=3)
    parser.add_argument("--table42-steps", type=int, default=600, help="per episode")
    parser.add_argument("--table42-images", type=int, default=150)
    parser.add_argument("--table43-episodes", type=int, default=10)
    parser.add_argument("--nees-runs", type=int, default=50)
    parser.add_argument("--frontends", nargs="+", default=list(FRONTENDS), choices=FRONTENDS)
    parser.add_argument("--seed", type=int, default=300)
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    results_path = args.out / "results.json"
    results = json.loads(results_path.read_text()) if results_path.exists() else {}
    markdown = {}
    if "table41" in args.only:
        results["table41"] = back_end_experiment(
            "table41",
            "patrol",
            60.0 * args.table41_minutes,
            args.table41_episodes,
            args.seed,
            tuple(args.frontends),
            args.out,
        )
    if "table43" in args.only:
        results["table43"] = back_end_experiment(
            "table43",
            "square",
            60.0,
            args.table43_episodes,
            args.seed + 1000,
            tuple(args.frontends),
            args.out,
        )
    if "table42" in args.only:
        import front_ends  # benchmarks/front_ends.py, beside this script

        summary, records = front_ends.run_walking(
            args.seed + 2000,
            episodes=args.table42_episodes,
            steps=args.table42_steps,
            images=args.table42_images,
            cnn_config=CnnDetectorConfig(),
        )
        (args.out / "table42_predictions.json").write_text(json.dumps(records) + "\n")
        results["table42"] = {"summary": summary, "markdown": front_ends.markdown(summary)}
    if "nees" in args.only:
        results["nees"] = consistency(args.nees_runs, args.seed + 3000, args.out)
    if "table41" in results:
        r = results["table41"]
        markdown["table41"] = table_41_markdown(r["rows"], r["episodes"], r["episode_s"] / 60)
    if "table42" in results:
        markdown["table42"] = results["table42"]["markdown"]
    if "table43" in results:
        markdown["table43"] = table_43_markdown(
            results["table43"]["rows"], results["table43"]["episodes"]
        )
    if "nees" in results:
        markdown["nees"] = nees_markdown(results["nees"])
    results_path.write_text(json.dumps(results, indent=2))
    (args.out / "tables.md").write_text("\n\n".join(markdown[k] for k in sorted(markdown)) + "\n")
    print(f"wrote {results_path} and {args.out / 'tables.md'}")


if __name__ == "__main__":
    main()
