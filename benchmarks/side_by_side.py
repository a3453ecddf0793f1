"""A benchmark script of this checkout and of an earlier one, run at the same time, one core each.

    git worktree add /tmp/before <commit>
    python benchmarks/side_by_side.py --baseline /tmp/before \\
        --out benchmarks/results/env_speed_before_after.json benchmarks/env_speed.py --steps 300

On a shared, noisy machine two timings taken minutes apart differ by tens of percent; two
processes running together share the same load, so their ratio is what the change did. The
earlier checkout runs its own copy of the script with ``PYTHONPATH`` at its root (so that it
imports its own packages, ahead of this checkout's editable install); this checkout runs the
script as it is. Both get ``OMP_NUM_THREADS=1`` and write their JSON to a temporary ``--out``
(the script must take one, for a file or a directory); ``--out`` here receives
``{"script", "args", "before", "after"}`` with each side's commit and JSON.

``--pin`` pins each side to a core of its own (``os.sched_setaffinity``) and runs the pair
twice, the cores swapped the second time: left to the scheduler, a process that briefly uses
more threads (OpenCV's) or lands on the slower core moves the ratio by ten per cent or more.
``--out`` then receives ``{"script", "args", "pinned": [round, round]}``, each round as above
plus ``"cores"``.
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent


def commit_of(checkout: Path) -> str:
    """The commit ``checkout`` is at (``git rev-parse HEAD``), with ``+dirty`` if it has
    uncommitted changes to tracked files."""
    head = subprocess.run(
        ["git", "-C", str(checkout), "rev-parse", "HEAD"], capture_output=True, text=True
    )
    if head.returncode != 0:
        raise ValueError(f"{checkout} is not a git checkout: {head.stderr.strip()}")
    dirty = subprocess.run(
        ["git", "-C", str(checkout), "diff", "--quiet", "HEAD"], capture_output=True
    ).returncode
    return head.stdout.strip() + ("+dirty" if dirty else "")


def side_by_side(
    baseline: Path, script: str, args: list[str], cores: tuple[int, int] | None = None
) -> dict[str, Any]:
    """Run ``script`` (a path relative to a checkout's root) with ``args`` in ``baseline`` and
    in this checkout at once (pinned to ``cores``, before's and after's, if given); return
    both sides' commits and JSON results."""
    if not (baseline / script).is_file():
        raise ValueError(f"{baseline / script} does not exist: --baseline must be a checkout")
    if not (ROOT / script).is_file():
        raise ValueError(f"{ROOT / script} does not exist")
    sides = {"before": baseline.resolve(), "after": ROOT}
    with tempfile.TemporaryDirectory() as scratch:
        outs = {side: Path(scratch) / side / "result.json" for side in sides}
        running = {}
        for k, (side, root) in enumerate(sides.items()):
            env = {**os.environ, "OMP_NUM_THREADS": "1"}
            if side == "before":
                env["PYTHONPATH"] = str(root)
            command = [sys.executable, script, *args, "--out", str(outs[side])]
            core = None if cores is None else cores[k]
            running[side] = subprocess.Popen(
                command,
                cwd=root,
                env=env,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE,
                preexec_fn=None if core is None else functools.partial(_pin, core),
            )
        for side, process in running.items():
            _, stderr = process.communicate()
            if process.returncode != 0:
                tail = stderr.decode(errors="replace")[-2000:]
                raise RuntimeError(f"the {side} run failed ({process.returncode}):\n{tail}")
        return {
            "script": script,
            "args": args,
            **{
                side: {"commit": commit_of(root), "result": _read_result(outs[side])}
                for side, root in sides.items()
            },
        }


def _pin(core: int) -> None:
    """Run this (child) process on ``core`` alone."""
    os.sched_setaffinity(0, {core})


def _read_result(out: Path) -> Any:
    """The JSON a script wrote to ``out``: the file, or the one ``.json`` file in it when the
    script took ``--out`` for a directory (as ``no_poles_patrols.py`` does)."""
    if out.is_dir():
        written = sorted(out.glob("*.json"))
        if len(written) != 1:
            raise RuntimeError(f"expected one JSON file in {out}, found {len(written)}")
        out = written[0]
    return json.loads(out.read_text())


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--baseline", type=Path, required=True, help="an earlier checkout")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument(
        "--pin", action="store_true", help="one core each, run twice with the cores swapped"
    )
    parser.add_argument("script", help="the benchmark, relative to a checkout's root")
    parser.add_argument("args", nargs=argparse.REMAINDER, help="the benchmark's own arguments")
    args = parser.parse_args()
    if args.pin:
        cores = sorted(os.sched_getaffinity(0))[:2]
        if len(cores) < 2:
            raise SystemExit("--pin needs two cores")
        rounds = [
            {**side_by_side(args.baseline, args.script, args.args, pair), "cores": list(pair)}
            for pair in ((cores[0], cores[1]), (cores[1], cores[0]))
        ]
        result: dict[str, Any] = {"script": args.script, "args": args.args, "pinned": rounds}
    else:
        result = side_by_side(args.baseline, args.script, args.args)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
