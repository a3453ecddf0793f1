"""Plot learning curves from the ``monitor/*.monitor.csv`` files that ``agents.train`` writes.

    python -m agents.learning_curves runs/av_seed0 runs/av_seed1 runs/av_seed2 \
        --out docs/learning_curves/active_vision.png --title SPL/ActiveVision-v1

Each run folder is one line: the episode returns of all its envs in the order they ended,
against the agent's steps taken by then (env steps; under an options wrapper that skips steps
without a choice, such as :class:`agents.striker_options.StrikerOptions`, the choices),
smoothed by a moving mean over ``--window`` episodes. ``--baseline NAME=VALUE`` draws a
horizontal line (e.g. a scripted policy's return).
Needs matplotlib (the ``train`` extra).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path

import numpy as np


def read_monitor(run: Path) -> tuple[np.ndarray, np.ndarray]:
    """Steps taken (E,) when each of the run's E episodes ended, and their returns (E,), from
    all ``run/monitor/*.monitor.csv`` files (SB3's ``Monitor``: a JSON line with ``t_start``,
    then ``r,l,t`` rows, t in seconds since ``t_start``), ordered by when they ended."""
    files = sorted((run / "monitor").glob("*.monitor.csv"))
    if not files:
        raise ValueError(f"run {str(run)!r} has no monitor/*.monitor.csv files")
    rows: list[tuple[float, float, float]] = []
    for path in files:
        with path.open() as handle:
            header = json.loads(next(handle).lstrip("#"))  # when this env started (epoch s)
            start = float(header["t_start"])
            rows += [
                (start + float(r["t"]), float(r["l"]), float(r["r"]))
                for r in csv.DictReader(handle)
            ]
    if not rows:
        raise ValueError(f"run {str(run)!r} has no finished episode yet")
    rows.sort()
    lengths = np.array([r[1] for r in rows])
    return np.cumsum(lengths), np.array([r[2] for r in rows])


def moving_mean(values: np.ndarray, window: int) -> np.ndarray:
    """Mean of each value and the up to ``window - 1`` before it (same length)."""
    if window < 1:
        raise ValueError(f"window must be >= 1, got {window}")
    sums = np.cumsum(np.concatenate([[0.0], values]))
    idx = np.arange(1, len(values) + 1)
    start = np.maximum(idx - window, 0)
    return (sums[idx] - sums[start]) / (idx - start)


def plot(
    runs: list[Path],
    out: Path,
    title: str,
    window: int,
    baselines: dict[str, float],
) -> Path:
    """Write the PNG ``out`` with one smoothed return curve per run folder."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4), dpi=100)
    for run in runs:
        steps, returns = read_monitor(run)
        ax.plot(steps, moving_mean(returns, window), label=run.name)
    for name, value in baselines.items():
        ax.axhline(value, linestyle="--", color="grey", linewidth=1)
        ax.annotate(name, (0, value), textcoords="offset points", xytext=(4, 3), fontsize=8)
    ax.set_xlabel("agent steps (one per choice under an options wrapper)")
    ax.set_ylabel(f"episode return (moving mean of {window})")
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    plt.close(fig)
    return out


def parse_baselines(pairs: list[str]) -> dict[str, float]:
    """``NAME=VALUE`` strings to a dict of finite floats; ValueError naming the pair
    otherwise."""
    out: dict[str, float] = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not sep or not name or not math.isfinite(number):
            raise ValueError(f"--baseline takes NAME=VALUE with a finite VALUE, got {pair!r}")
        out[name] = number
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("runs", nargs="+", type=Path, help="run folders of agents.train")
    parser.add_argument("--out", type=Path, required=True, help="PNG to write (.png)")
    parser.add_argument("--title", default="", help="the plot's title")
    parser.add_argument(
        "--window", type=int, default=10, help="episodes in each moving mean (>= 1)"
    )
    parser.add_argument(
        "--baseline",
        nargs="*",
        default=[],
        metavar="NAME=VALUE",
        help="dashed reference lines, e.g. scan=-249",
    )
    args = parser.parse_args(argv)
    if args.window < 1:
        parser.error(f"--window must be >= 1, got {args.window}")
    if args.out.suffix.lower() != ".png":
        parser.error(f"--out must name a .png file, got {str(args.out)!r}")
    try:
        written = plot(args.runs, args.out, args.title, args.window, parse_baselines(args.baseline))
    except (ValueError, OSError) as error:
        parser.error(str(error))
    print(written)


if __name__ == "__main__":
    main()
