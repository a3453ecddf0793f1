"""Multi-robot tracking over one-minute episodes of ``SPL/ActiveVision-v1``, per robot front end.

What: how well the confirmed robot tracks (``info["perception"]``) follow the other robots,
with 4 and 8 other robots on the field, for the robot front ends ``vision`` (seed 004 §6.2
field-edge indents + sonar check), ``cnn`` (the packaged CNN's ``robot`` class) and, as a
reference, ``oracle`` (truth plus noise). Poles are the default CNN front end in every run.

How: one-minute episodes (600 control steps of 0.1 s; the task's default ``episode_s``). Our
robot walks the env's scripted patrol; the agent's action is the head, driven by a scripted,
truth-informed policy (:func:`choose_target`): every 2 s it picks one of the other robots
within 3 m of ours at random (any other robot when none is that near) and looks at it with a
random offset of up to ±15° in yaw and a random pitch (``head_policy`` of
``benchmarks/robot_detection.py``). Truth: ``info["ground_truth"]`` (our pose, the other
robots, field frame). Per step:

- **GOSPA** (:func:`gospa`; alpha = 2, p = 2, cut-off c = 1 m) split into localisation,
  missed and false parts (m², they add up to GOSPA²), averaged over the steps;
- **CLEAR MOT** (:class:`ClearMot`; Bernardin & Stiefelhagen 2008): MOTA, MOTP and ID
  switches, matches within 0.5 m, correspondences kept while they stay within 0.5 m;
- the **position error** of the confirmed tracks matched (CLEAR, 0.5 m) to robots within 3 m
  (mean, median, p90: the acceptance figure is the mean, <= 0.15 m with 4 other robots);
- the **false-track rate**: confirmed tracks with no robot within 0.5 m, per track-step
  (within 3 m of our robot, and over all confirmed tracks), with a guess at each false
  track's cause (the nearest robot, pole or goal post, off the field);
- the **missed rate**: robots within 3 m that *should be tracked* (wholly in the camera image
  and at most 30 % covered by a nearer robot, now or at some step in the last 2 s: the
  tracker drops a track 2 s unseen) without a confirmed track within 0.5 m; and the plain
  share of the robots within 3 m that have a confirmed track within 0.5 m;
- **timing**: ``env.unwrapped.step_times`` (wall-clock s of the step's physics, render,
  sensors and perception); the ratio of mean perception to mean render time per front end
  (acceptance: < 0.6 for poles + robots).

The region of interest is the disc of 3 m around our robot's *true* position. Its boundary:
the GOSPA and CLEAR assignments are made between the robots and the tracks within 3.5 m
(3 m + a 0.5 m margin), and then a localisation term or match counts when its robot is within
3 m, a missed robot when it is within 3 m, a false track when the track is within 3 m. So a
track at 3.2 m of a robot at 2.9 m is a match, a track at 2.9 m of a robot at 3.2 m counts
neither as a false track nor as anything else, and a robot at 3.2 m is never missed.

Held-out seeds 100-109 by default (``--episodes`` takes the first that many of 100, 101, ...;
``--seeds`` any list). Torch runs on one thread (``--torch-threads``), as in the other
benchmarks: with torch's default of one thread per core, the CNN on a loaded two-core host took
50-190 ms a frame instead of 3 ms, and the timing would measure the contention::

    python benchmarks/robot_tracking.py --robots 4 8 --frontends vision cnn oracle
    python benchmarks/robot_tracking.py --robots 4 --frontends vision --set self_pose=field_features

``--set KEY=VALUE`` passes env config overrides (``agents.evaluate``'s), e.g.
``self_pose=field_features`` to localise from the field's lines instead of the poles.

Writes ``benchmarks/results/robot_tracking.json`` (``robot_tracking_<KEY=VALUE>.json`` with
``--set``, unless ``--out`` names it; per episode and summary),
``robot_tracking.md`` (the table) and ``robot_tracking_gospa.png`` (GOSPA over the first
seed's episode, per configuration).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import gymnasium as gym
import numpy as np
import torch
from numpy.typing import NDArray
from robot_detection import head_policy as look_at
from robot_detection import parse_seeds
from robot_detection import wholly_in_view as in_view
from scipy.optimize import linear_sum_assignment
from seed000_experiments import series_plot

import spl_env  # noqa: F401  (registers the envs)
from agents.baselines import HeadScan
from agents.evaluate import add_overrides_argument, parse_overrides
from perception.geometry import FloatArray
from perception.representations import ROBOT_TRACKS

ENV_ID = "SPL/ActiveVision-v1"
RADIUS_M = 3.0  # region of interest around our robot's true position
MARGIN_M = 0.5  # robots and tracks this far beyond RADIUS_M take part in the assignments
GOSPA_C_M = 1.0  # GOSPA cut-off distance
GOSPA_P = 2
GOSPA_ALPHA = 2
MATCH_M = 0.5  # CLEAR MOT match threshold; a track this near a robot tracks it
RECENT_S = 2.0  # a robot in view within this long ago should be tracked
HEAD_SWITCH_S = 2.0  # the head policy picks a new robot this often
CAUSE_M = 0.5  # a false track this near a pole or goal post is blamed on it
RESULTS = Path("benchmarks/results")
HEADS = {
    "robots": "a random robot within 3 m every 2 s, +-15 deg yaw offset, pitch 0-0.4 rad",
    "scan": "agents.baselines.HeadScan: yaw 90 deg sin(2 pi t / 4 s), level pitch",
}


# ----- metrics ------------------------------------------------------------------------------
def distances(a: FloatArray, b: FloatArray) -> FloatArray:
    """Pairwise Euclidean distances (len(a), len(b)) (m) between points (n, 2) and (m, 2)."""
    return np.hypot(*(a[:, None, :] - b[None, :, :]).transpose(2, 0, 1)).reshape(len(a), len(b))


def gospa(
    truth: FloatArray,
    tracks: FloatArray,
    c: float = GOSPA_C_M,
    p: int = GOSPA_P,
    alpha: int = GOSPA_ALPHA,
) -> tuple[list[tuple[int, int, float]], NDArray[np.bool_], NDArray[np.bool_]]:
    """The optimal GOSPA assignment between ``truth`` (n, 2) and ``tracks`` (m, 2) (m, field
    frame): the assigned pairs ``(truth index, track index, distance m)`` and the masks (n,)
    of missed robots and (m,) of false tracks.

    GOSPA (Rahmathullah, García-Fernández & Svensson, "Generalized optimal sub-pattern
    assignment metric", FUSION 2017), for ``alpha = 2``::

        d = ( min over assignments  sum_pairs d(x, y)^p + c^p / 2 (missed + false) )^(1/p)

    over assignments of pairs closer than ``c``; equivalently an optimal assignment of the
    cost ``min(d, c)^p`` (scipy's ``linear_sum_assignment``), pairs at ``c`` or more being
    left unassigned (each then costs ``c^p / 2`` per side, ``c^p`` together).
    """
    if alpha != 2:
        raise ValueError(f"gospa implements alpha = 2 only, got {alpha}")
    gaps = distances(truth, tracks)
    rows, cols = linear_sum_assignment(np.minimum(gaps, c) ** p) if gaps.size else ([], [])
    pairs = [(int(i), int(j), float(gaps[i, j])) for i, j in zip(rows, cols, strict=True)]
    pairs = [pair for pair in pairs if pair[2] < c]
    missed = np.ones(len(truth), dtype=bool)
    false = np.ones(len(tracks), dtype=bool)
    for i, j, _ in pairs:
        missed[i], false[j] = False, False
    return pairs, missed, false


def gospa_terms(
    truth: FloatArray, tracks: FloatArray, truth_in: NDArray[np.bool_], track_in: NDArray[np.bool_]
) -> dict[str, float]:
    """One step's GOSPA parts (m²) over the region of interest: ``localisation`` (sum of d^2
    over pairs whose robot is inside), ``missed`` and ``false`` (c^2 / 2 per robot inside
    left unassigned, per track inside left unassigned); ``gospa`` (m) the root of their sum,
    and the counts ``n_missed``, ``n_false``. ``truth`` (n, 2) and ``tracks`` (m, 2) are the
    robots and tracks within the assignment radius, ``truth_in`` and ``track_in`` (bool)
    mark those inside the region."""
    pairs, missed, false = gospa(truth, tracks)
    half = GOSPA_C_M**GOSPA_P / GOSPA_ALPHA
    loc = sum(d**GOSPA_P for i, _, d in pairs if truth_in[i])
    n_missed = int(np.count_nonzero(missed & truth_in))
    n_false = int(np.count_nonzero(false & track_in))
    total = loc + half * (n_missed + n_false)
    return {
        "gospa": total ** (1.0 / GOSPA_P),
        "localisation": loc,
        "missed": half * n_missed,
        "false": half * n_false,
        "n_missed": n_missed,
        "n_false": n_false,
    }


@dataclass
class ClearMot:
    """CLEAR MOT (Bernardin & Stiefelhagen, "Evaluating multiple object tracking performance:
    the CLEAR MOT metrics", EURASIP JIVP 2008) over one episode, matches within ``MATCH_M``.

    Per step: a robot's correspondence (track id) of the previous step is kept while its track
    is still within the threshold; the rest are assigned optimally by distance. A match whose
    robot had a different track at its last match is an ID switch; a *swap* when that track
    is still confirmed (the tracks exchanged robots or a second one took over), else a
    re-acquisition (the old track was dropped). Counted in the region of interest (module
    doc): ``gt`` robots, ``misses`` robots unmatched, ``false`` tracks unmatched,
    ``switches`` and ``swaps``, ``errors`` (the matches' distances, m)."""

    last: dict[int, int] = field(default_factory=dict)  # robot index -> last matched track id
    previous: dict[int, int] = field(default_factory=dict)  # the previous step's matches
    gt: int = 0
    misses: int = 0
    false: int = 0
    switches: int = 0
    swaps: int = 0
    errors: list[float] = field(default_factory=list)

    def step(
        self,
        robot_ids: NDArray[np.int64],
        truth: FloatArray,
        track_ids: NDArray[np.int64],
        tracks: FloatArray,
        truth_in: NDArray[np.bool_],
        track_in: NDArray[np.bool_],
    ) -> list[tuple[int, int, float]]:
        """Match one step: robots ``robot_ids`` at ``truth`` (n, 2) and tracks ``track_ids`` at
        ``tracks`` (m, 2) (field frame, m); returns the matches (truth row, track row, m)."""
        gaps = distances(truth, tracks)
        column = {int(t): j for j, t in enumerate(track_ids)}
        matches: list[tuple[int, int, float]] = []
        for i, rid in enumerate(robot_ids):
            j = column.get(self.previous.get(int(rid), -1))
            if j is not None and gaps[i, j] < MATCH_M:
                matches.append((i, j, float(gaps[i, j])))
        free_rows = [i for i in range(len(truth)) if i not in {m[0] for m in matches}]
        free_cols = [j for j in range(len(tracks)) if j not in {m[1] for m in matches}]
        if free_rows and free_cols:
            sub = gaps[np.ix_(free_rows, free_cols)]
            rows, cols = linear_sum_assignment(np.where(sub < MATCH_M, sub, 1e6))
            for r, k in zip(rows, cols, strict=True):
                if sub[r, k] < MATCH_M:
                    matches.append((free_rows[r], free_cols[k], float(sub[r, k])))
        self._count(robot_ids, track_ids, matches, truth_in, track_in)
        return matches

    def _count(
        self,
        robot_ids: NDArray[np.int64],
        track_ids: NDArray[np.int64],
        matches: list[tuple[int, int, float]],
        truth_in: NDArray[np.bool_],
        track_in: NDArray[np.bool_],
    ) -> None:
        """Add one step's matches to the counts and remember the correspondences."""
        matched_rows = {i for i, _, _ in matches}
        matched_cols = {j for _, j, _ in matches}
        self.gt += int(np.count_nonzero(truth_in))
        self.misses += sum(1 for i in np.flatnonzero(truth_in) if i not in matched_rows)
        self.false += sum(1 for j in np.flatnonzero(track_in) if j not in matched_cols)
        self.previous = {}
        present = {int(t) for t in track_ids}
        for i, j, d in matches:
            rid, tid = int(robot_ids[i]), int(track_ids[j])
            if truth_in[i]:
                self.errors.append(d)
                switch = rid in self.last and self.last[rid] != tid
                self.switches += int(switch)
                self.swaps += int(switch and self.last[rid] in present)
            self.last[rid] = tid
            self.previous[rid] = tid


# ----- the episode --------------------------------------------------------------------------
def choose_target(rng: np.random.Generator, robots: FloatArray, pose: FloatArray) -> int:
    """Index of the other robot to look at: a random one of those within ``RADIUS_M`` of our
    true ``pose`` (3,), else a random one of all ``robots`` (R, 3) (field frame, m)."""
    near = np.flatnonzero(np.hypot(*(robots[:, :2] - pose[:2]).T) < RADIUS_M)
    pool = near if len(near) else np.arange(len(robots))
    return int(rng.choice(pool))


def false_cause(
    track: FloatArray, robots: FloatArray, poles: FloatArray, posts: FloatArray, half: FloatArray
) -> str:
    """A guess at why a false track sits at ``track`` (2,) (field frame, m): a robot within
    1 m (``robot_0.5-1m``), a pole or goal post within ``CAUSE_M``, off the field lines
    (``half`` (2,) the half length and width), else ``other``."""
    if len(robots) and distances(track[None], robots).min() < 1.0:
        return "robot_0.5-1m"
    if distances(track[None], poles).min() < CAUSE_M:
        return "pole"
    if distances(track[None], posts).min() < CAUSE_M:
        return "goal_post"
    if np.any(np.abs(track) > half):
        return "off_field"
    return "other"


@dataclass
class Counts:
    """Sums over the steps of one or more episodes (the metrics are ratios of these)."""

    steps: int = 0
    gospa: float = 0.0  # sum of the steps' GOSPA (m)
    gospa_localisation: float = 0.0  # sums of the parts (m²)
    gospa_missed: float = 0.0
    gospa_false: float = 0.0
    mot_gt: int = 0
    mot_misses: int = 0
    mot_false: int = 0
    mot_switches: int = 0
    mot_swaps: int = 0
    errors: list[float] = field(default_factory=list)  # matched robots within 3 m (m)
    error_ages: list[float] = field(default_factory=list)  # s since each one's track was seen
    relative_errors: list[float] = field(default_factory=list)  # the same in our robot's frame
    slam_error: float = 0.0  # sum over the steps of the SLAM position error (m)
    near: int = 0  # robot-steps within 3 m
    near_tracked: int = 0  # ... with a confirmed track within MATCH_M
    should: int = 0  # robot-steps within 3 m that should be tracked
    should_tracked: int = 0
    confirmed: int = 0  # confirmed track-steps (any range)
    confirmed_false: int = 0  # ... with no robot within MATCH_M
    confirmed_in: int = 0  # confirmed track-steps within 3 m
    confirmed_in_false: int = 0
    false_causes: dict[str, int] = field(default_factory=dict)  # of the false tracks within 3 m
    track_ids: int = 0  # distinct confirmed track ids
    times: dict[str, float] = field(default_factory=dict)  # summed step_times (s)

    def add(self, other: Counts) -> None:
        """Add ``other``'s sums to these."""
        for name, value in vars(other).items():
            mine = getattr(self, name)
            if isinstance(value, list):
                mine.extend(value)
            elif isinstance(value, dict):
                for key, v in value.items():
                    mine[key] = mine.get(key, 0) + v
            else:
                setattr(self, name, mine + value)


def _ratio(num: float, den: float, digits: int = 4) -> float | None:
    return round(num / den, digits) if den else None


def _mean(x: NDArray[np.float64]) -> float | None:
    return round(float(x.mean()), 4) if len(x) else None


def metrics(c: Counts) -> dict[str, Any]:
    """The reported figures of ``c`` (module doc); distances m, GOSPA parts m², times ms."""
    e = np.array(c.errors)
    fresh = np.array(c.error_ages) < 0.05  # the track took a sighting this step
    minutes = c.steps * 0.1 / 60.0
    mean_times = {k: v / max(c.steps, 1) for k, v in c.times.items()}
    return {
        "steps": c.steps,
        "gospa_m": _ratio(c.gospa, c.steps),
        "gospa_localisation_m2": _ratio(c.gospa_localisation, c.steps),
        "gospa_missed_m2": _ratio(c.gospa_missed, c.steps),
        "gospa_false_m2": _ratio(c.gospa_false, c.steps),
        "mota": round(1.0 - (c.mot_misses + c.mot_false + c.mot_switches) / c.mot_gt, 4)
        if c.mot_gt
        else None,
        "motp_m": round(float(e.mean()), 4) if len(e) else None,
        "id_switches": c.mot_switches,
        "id_switches_per_min": _ratio(c.mot_switches, minutes, 3),
        "position_error_mean_m": round(float(e.mean()), 4) if len(e) else None,
        "position_error_median_m": round(float(np.median(e)), 4) if len(e) else None,
        "position_error_p90_m": round(float(np.percentile(e, 90)), 4) if len(e) else None,
        "position_error_robot_frame_mean_m": _mean(np.array(c.relative_errors)),
        "position_error_seen_now_mean_m": _mean(e[fresh]),
        "position_error_coasting_mean_m": _mean(e[~fresh]),
        "coasting_share": _ratio(int((~fresh).sum()), len(e)),
        "slam_position_error_mean_m": _ratio(c.slam_error, c.steps),
        "id_swaps": c.mot_swaps,
        "id_reacquisitions": c.mot_switches - c.mot_swaps,
        "matched_track_steps": len(e),
        "robot_steps_within_3m": c.near,
        "tracked_share_within_3m": _ratio(c.near_tracked, c.near),
        "should_track_steps": c.should,
        "missed_rate": _ratio(c.should - c.should_tracked, c.should),
        "false_track_rate_within_3m": _ratio(c.confirmed_in_false, c.confirmed_in),
        "false_track_rate_all": _ratio(c.confirmed_false, c.confirmed),
        "false_track_causes_within_3m": dict(Counter(c.false_causes).most_common()),
        "mot_counts": {
            "gt": c.mot_gt,
            "misses": c.mot_misses,
            "false": c.mot_false,
            "switches": c.mot_switches,
            "swaps": c.mot_swaps,
        },
        "confirmed_track_ids": c.track_ids,
        "ms_per_step": {k: round(1e3 * v, 2) for k, v in mean_times.items()},
        "perception_over_render": _ratio(
            mean_times.get("perception", 0.0), mean_times.get("render", 0.0), 3
        ),
    }


@dataclass
class Scene:
    """What one step's scoring reads (field frame, m)."""

    pose: FloatArray  # our true pose (3,)
    slam_pose: FloatArray  # our pose as SLAM believes it (3,)
    robots: FloatArray  # other robots (R, 2)
    tracks: FloatArray  # confirmed tracks (m, 2)
    track_ids: NDArray[np.int64]  # (m,)
    track_ages: FloatArray  # (m,) s since each track's last sighting
    visible: NDArray[np.bool_]  # (R,) in view now


def read_scene(env: Any, info: dict[str, Any]) -> Scene:
    """The step's truth and confirmed tracks from ``info`` (``info_level="full"``); the
    tracks' ages from the env's perception output and the robots in view from geometry."""
    p, truth = info["perception"], info["ground_truth"]
    tracked = p["robots_tracked"]
    u = env.unwrapped
    seen = {t.track_id: t.last_seen_s for t in u.perception_output[ROBOT_TRACKS]}
    track_ids = p["robot_track_ids"][tracked]
    return Scene(
        pose=truth["robot_pose"],
        slam_pose=p["pose"],
        robots=truth["robots"][:, :2],
        tracks=p["robots"][tracked],
        track_ids=track_ids,
        track_ages=np.array([u.world_state.time_s - seen[int(t)] for t in track_ids]),
        visible=in_view(env),
    )


@dataclass
class Landmarks:
    """Fixed field objects for the false-track causes (field frame, m)."""

    poles: FloatArray  # (L, 2)
    posts: FloatArray  # (4, 2)
    half: FloatArray  # (2,) half length and half width of the field lines


def to_robot_frame(pose: FloatArray, point: FloatArray) -> FloatArray:
    """``point`` (2,) in the field frame seen from ``pose`` (3,): robot frame (m)."""
    c, s = np.cos(pose[2]), np.sin(pose[2])
    d = point - pose[:2]
    return np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])


def relative_error(scene: Scene, robot: int, track: int) -> float:
    """Error (m) of a track as a position relative to our robot: the track seen from the SLAM
    pose against the robot seen from our true pose, which leaves out our own localisation
    error."""
    believed = to_robot_frame(scene.slam_pose, scene.tracks[track])
    true = to_robot_frame(scene.pose, scene.robots[robot])
    return float(np.hypot(*(believed - true)))


def score_step(
    scene: Scene, last_view_s: FloatArray, time_s: float, mot: ClearMot, marks: Landmarks
) -> tuple[Counts, float]:
    """One step's :class:`Counts` (times excluded) and its GOSPA (m); ``last_view_s`` (R,)
    the time (s) each robot was last in view (updated here), ``mot`` the episode's CLEAR
    MOT state."""
    c = Counts(steps=1)
    last_view_s[scene.visible] = time_s
    robot_range = np.hypot(*(scene.robots - scene.pose[:2]).T)
    track_range = np.hypot(*(scene.tracks - scene.pose[:2]).T).reshape(-1)
    rows = np.flatnonzero(robot_range < RADIUS_M + MARGIN_M)
    cols = np.flatnonzero(track_range < RADIUS_M + MARGIN_M)
    truth_in = robot_range[rows] < RADIUS_M
    track_in = track_range[cols] < RADIUS_M
    terms = gospa_terms(scene.robots[rows], scene.tracks[cols], truth_in, track_in)
    c.gospa = terms["gospa"]
    c.gospa_localisation = terms["localisation"]
    c.gospa_missed, c.gospa_false = terms["missed"], terms["false"]
    before = (mot.gt, mot.misses, mot.false, mot.switches, mot.swaps)
    ids, tracks = scene.track_ids[cols], scene.tracks[cols]
    matches = mot.step(rows, scene.robots[rows], ids, tracks, truth_in, track_in)
    c.mot_gt, c.mot_misses = mot.gt - before[0], mot.misses - before[1]
    c.mot_false, c.mot_switches = mot.false - before[2], mot.switches - before[3]
    c.mot_swaps = mot.swaps - before[4]
    inner = [(j, d) for i, j, d in matches if truth_in[i]]
    c.errors = [d for _, d in inner]
    c.error_ages = [float(scene.track_ages[cols][j]) for j, _ in inner]
    c.relative_errors = [
        relative_error(scene, int(rows[i]), int(cols[j])) for i, j, _ in matches if truth_in[i]
    ]
    gaps = distances(scene.robots, scene.tracks)  # (R, m)
    has_track = (gaps < MATCH_M).any(axis=1) if gaps.size else np.zeros(len(gaps), dtype=bool)
    near = robot_range < RADIUS_M
    should = near & (time_s - last_view_s <= RECENT_S + 1e-9)
    c.near, c.near_tracked = int(near.sum()), int((near & has_track).sum())
    c.should, c.should_tracked = int(should.sum()), int((should & has_track).sum())
    false = ~(gaps < MATCH_M).any(axis=0) if gaps.size else np.ones(len(scene.tracks), bool)
    c.confirmed, c.confirmed_false = len(scene.tracks), int(false.sum())
    inside = track_range < RADIUS_M
    c.confirmed_in, c.confirmed_in_false = int(inside.sum()), int((inside & false).sum())
    for j in np.flatnonzero(inside & false):
        cause = false_cause(scene.tracks[j], scene.robots, marks.poles, marks.posts, marks.half)
        c.false_causes[cause] = c.false_causes.get(cause, 0) + 1
    return c, c.gospa


def make_env(
    frontend: str, n_robots: int, episode_s: float, overrides: dict[str, Any] | None = None
) -> gym.Env:
    """The env: ``frontend`` robot sightings among ``n_robots`` other robots, full info, and
    the env config ``overrides`` (``--set``)."""
    settings = {
        "robot_frontend": frontend,
        "n_other_robots": n_robots,
        "episode_s": episode_s,
        "info_level": "full",
    }
    return gym.make(ENV_ID, **{**settings, **(overrides or {})})


def run_episode(env: gym.Env, seed: int, head: str) -> tuple[Counts, list[float], str | None]:
    """One episode on ``seed``: its :class:`Counts`, its GOSPA per step (m) and None, or, if a
    step raised, the counts so far and the error (``"step k: Type: message"``). ``head``:
    ``"robots"`` (:func:`choose_target`) or ``"scan"`` (``agents.baselines.HeadScan``)."""
    u = env.unwrapped
    rng = np.random.default_rng(10_000 + seed)
    obs, info = env.reset(seed=seed)
    scan = HeadScan.from_config(u.config)
    dims = u.config.scene.dimensions
    marks = Landmarks(
        poles=info["ground_truth"]["landmarks"],
        posts=np.asarray(dims.goal_posts())[:, :2],
        half=np.array([dims.half_length_m, dims.half_width_m]),
    )
    n_others = len(info["ground_truth"]["robots"])
    last_view_s = np.full(n_others, -np.inf)
    mot, total, series = ClearMot(), Counts(), []
    switch_every = round(HEAD_SWITCH_S / u.config.control_dt_s)
    target, offset, ids, error = 0, np.zeros(2), set(), None
    for step in range(u.config.max_steps):
        if step % switch_every == 0:
            truth = info["ground_truth"]
            target = choose_target(rng, truth["robots"], truth["robot_pose"])
            offset = np.array([rng.uniform(-0.26, 0.26), rng.uniform(0.0, 0.4)])
        try:
            action = scan.predict(obs)[0] if head == "scan" else look_at(env, rng, target, offset)
            obs, _, terminated, truncated, info = env.step(action)
        except Exception as err:  # a perception failure: reported, the episode left out
            error = f"step {step}: {type(err).__name__}: {err}"
            break
        times = u.step_times
        scene = read_scene(env, info)
        counts, g = score_step(scene, last_view_s, u.world_state.time_s, mot, marks)
        counts.slam_error = float(np.hypot(*(info["perception"]["pose"][:2] - scene.pose[:2])))
        counts.times = {k: float(v) for k, v in times.items()}
        total.add(counts)
        series.append(g)
        ids.update(int(t) for t in scene.track_ids)
        if terminated or truncated:
            break
    total.track_ids = len(ids)
    return total, series, error


# ----- reporting ----------------------------------------------------------------------------
def gospa_figure(series: dict[tuple[str, int], list[float]]) -> np.ndarray:
    """(H, W, 3) BGR: GOSPA (m, 1 s running mean) over the first completed episode of each
    configuration (the first seed unless it failed), one panel per number of other robots,
    one line per front end."""
    panels = []
    for n in sorted({n for _, n in series}):
        lines = {}
        for (frontend, m), values in series.items():
            if m == n and values:
                v = np.asarray(values)
                sums = np.cumsum(np.concatenate([[0.0], v]))
                start = np.maximum(np.arange(1, len(v) + 1) - 10, 0)
                lines[frontend] = (sums[1:] - sums[start]) / (np.arange(1, len(v) + 1) - start)
        steps = max(len(v) for v in lines.values())
        times = 0.1 * np.arange(1, steps + 1)
        title = f"GOSPA (m, c = 1 m, 1 s mean), robots within 3 m, first seed, {n} others"
        panels.append(series_plot(times, lines, title, y_max=GOSPA_C_M * 2.0))
    return np.vstack(panels)


def diagnostics(summary: dict[str, Any]) -> str:
    """The diagnostic table: error of tracks seen this step and coasting, self-pose error, ID switch
    kinds, track ids started, false-track causes."""
    rows = [
        "| front end | others | error robot frame (m) | error seen now / coasting (m) "
        "| coasting share | self-pose error (m) "
        "| ID swaps / re-acquisitions | confirmed ids | false tracks within 3 m by cause |",
        "|" + "---|" * 9,
    ]
    for key, m in summary.items():
        frontend, n = key.split("/")
        causes = ", ".join(f"{k} {v}" for k, v in m["false_track_causes_within_3m"].items())
        rows.append(
            f"| {frontend} | {n} | {m['position_error_robot_frame_mean_m']} | "
            f"{m['position_error_seen_now_mean_m']} / "
            f"{m['position_error_coasting_mean_m']} | {m['coasting_share']} | "
            f"{m['slam_position_error_mean_m']} | {m['id_swaps']} / {m['id_reacquisitions']} | "
            f"{m['confirmed_track_ids']} | {causes} |"
        )
    return "\n".join(rows)


def markdown(summary: dict[str, Any], setting: dict[str, Any]) -> str:
    """The summary table (one row per front end and number of other robots)."""
    head = (
        "| front end | others | GOSPA (m) | loc / missed / false (m²) | MOTA | MOTP (m) | "
        "ID sw. / min | pos. error mean / p90 (m) | false tracks | missed | tracked within 3 m "
        "| perception / render (ms) | ratio |"
    )
    rows = [head, "|" + "---|" * 13]
    for key, m in summary.items():
        frontend, n = key.split("/")
        t = m["ms_per_step"]
        rows.append(
            f"| {frontend} | {n} | {m['gospa_m']} | {m['gospa_localisation_m2']} / "
            f"{m['gospa_missed_m2']} / {m['gospa_false_m2']} | {m['mota']} | {m['motp_m']} | "
            f"{m['id_switches_per_min']} | {m['position_error_mean_m']} / "
            f"{m['position_error_p90_m']} | {m['false_track_rate_within_3m']} | "
            f"{m['missed_rate']} | {m['tracked_share_within_3m']} | "
            f"{t.get('perception')} / {t.get('render')} | {m['perception_over_render']} |"
        )
    rows += ["", diagnostics(summary)]
    notes = (
        f"\n{ENV_ID}, seeds {setting['seeds']}, {setting['episode_s']} s episodes (10 Hz), "
        f"head: {setting['head']}. Region: robots "
        "and tracks within 3 m of our true position (assignments within 3.5 m). False tracks: "
        "confirmed tracks within 3 m with no robot within 0.5 m, per track-step. Missed: "
        "robots within 3 m in view in the last 2 s without a confirmed track within 0.5 m. "
        f"Times: mean of `step_times` per step (torch on {setting['torch_threads']} thread) on "
        "the benchmark host (shared, 2 cores). Measured at commit "
        f"{setting.get('commit', '?')[:7]}.\n"
    )
    failures = [
        f"- {key}: seed {f['seed']} failed at {f['error']} (left out)\n"
        for key, m in summary.items()
        for f in m.get("failed_episodes", [])
    ]
    return "\n".join(rows) + "\n" + notes + ("\n" + "".join(failures) if failures else "")


def provenance() -> dict[str, Any]:
    """The commit measured and the package files changed since (read-only git queries)."""
    git = ["git", "-C", str(Path(__file__).resolve().parents[1])]
    try:
        head = subprocess.run([*git, "rev-parse", "HEAD"], capture_output=True, text=True)
        dirty = subprocess.run(
            [*git, "status", "--porcelain", "--", "perception", "spl_env"],
            capture_output=True,
            text=True,
        )
    except OSError:
        return {}
    return {"commit": head.stdout.strip(), "uncommitted": dirty.stdout.split("\n")[:-1]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--seeds",
        default=None,
        help="episode seeds, e.g. 100-104 (default: --episodes of 100, 101, ...)",
    )
    parser.add_argument("--episodes", type=int, default=10, help="seeds 100.. when no --seeds")
    parser.add_argument("--robots", type=int, nargs="+", default=[4, 8])
    parser.add_argument("--frontends", nargs="+", default=["vision", "cnn", "oracle"])
    parser.add_argument("--episode-s", type=float, default=60.0, help="episode length (s)")
    parser.add_argument("--head", choices=tuple(HEADS), default="robots")
    parser.add_argument("--torch-threads", type=int, default=1, help="torch intra-op threads")
    add_overrides_argument(parser)
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help="JSON path (robot_tracking[_<head other than robots>][_<overrides>].json)",
    )
    args = parser.parse_args()
    overrides = parse_overrides(args.set)
    if args.out is None:
        head = [] if args.head == "robots" else [args.head]
        args.out = RESULTS / ("_".join(["robot_tracking", *head, *args.set]) + ".json")
    torch.set_num_threads(args.torch_threads)
    seeds = parse_seeds(args.seeds) if args.seeds else list(range(100, 100 + args.episodes))
    setting = {
        "env": ENV_ID,
        "seeds": args.seeds or ",".join(str(s) for s in seeds),
        "episode_s": args.episode_s,
        "head": HEADS[args.head],
        "radius_m": RADIUS_M,
        "margin_m": MARGIN_M,
        "gospa": {"c_m": GOSPA_C_M, "p": GOSPA_P, "alpha": GOSPA_ALPHA},
        "match_m": MATCH_M,
        "recent_s": RECENT_S,
        "torch_threads": torch.get_num_threads(),
        "overrides": overrides,
        **provenance(),
    }
    episodes: list[dict[str, Any]] = []
    summary: dict[str, Any] = {}
    series: dict[tuple[str, int], list[float]] = {}
    started = time.perf_counter()
    for n in args.robots:
        for frontend in args.frontends:
            env = make_env(frontend, n, args.episode_s, overrides)
            pooled = Counts()
            failed = []
            for seed in seeds:
                t0 = time.perf_counter()
                counts, gospa_series, error = run_episode(env, seed, args.head)
                record = {"frontend": frontend, "robots": n, "seed": seed, **metrics(counts)}
                record["wall_s"] = round(time.perf_counter() - t0, 1)
                if error is None:
                    pooled.add(counts)
                    series.setdefault((frontend, n), gospa_series)
                else:  # left out of the summary; a fresh env for the next seed
                    record["error"] = error
                    failed.append({"seed": seed, "error": error})
                    env.close()
                    env = make_env(frontend, n, args.episode_s, overrides)
                episodes.append(record)
                print(json.dumps({k: record[k] for k in list(record)[:8]}), error, flush=True)
            env.close()
            summary[f"{frontend}/{n}"] = {**metrics(pooled), "failed_episodes": failed}
            write(args.out, setting, summary, episodes, time.perf_counter() - started)
    write(args.out, setting, summary, episodes, time.perf_counter() - started)
    image = gospa_figure(series)
    cv2.imwrite(str(args.out.with_name(args.out.stem + "_gospa.png")), image)
    print(json.dumps(summary, indent=1))


def write(
    out: Path,
    setting: dict[str, Any],
    summary: dict[str, Any],
    episodes: list[dict[str, Any]],
    wall_s: float,
) -> None:
    """The JSON (setting, summary, episodes) and the markdown table next to it."""
    out.parent.mkdir(parents=True, exist_ok=True)
    result = {
        "setting": {**setting, "wall_s": round(wall_s, 1)},
        "summary": summary,
        "episodes": episodes,
    }
    out.write_text(json.dumps(result, indent=1) + "\n")
    out.with_suffix(".md").write_text(markdown(summary, setting))


if __name__ == "__main__":
    main()
