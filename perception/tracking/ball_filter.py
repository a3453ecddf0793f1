"""A Kalman filter of the ball relative to our robot: rolling with friction, kicks as velocity
jumps, our own kicks known.

The state ``(x, y, vx, vy)`` (m, m/s) is the ball's position and ground velocity in the robot
frame (egocentric, as B-Human's ball model): sightings are measured there, and a correction of
the believed pose (a pole sighting) does not move the ball relative to the robot. The field
frame's estimate is that state composed with the believed pose, the pose's covariance added
(:func:`ball_in_field`).

Between frames the ball rolls straight and slows at a constant deceleration
``deceleration_mps2`` (rolling friction, Coulomb-like: the simulator's ball loses 0.11 m/s per
second at every speed once it rolls) until it stops::

    speed' = max(speed - a dt, 0),   position' = position + direction * (distance rolled)

and then the robot's own motion since the last frame (the odometry's ``(dx, dy, dθ)``) moves
the frame: ``p' = R(-dθ) (p - d)``, ``v' = R(-dθ) v``. The mean follows both exactly; the
covariance takes the friction as a known input, rolling the uncertainty on at constant velocity
(a friction Jacobian would collapse the velocity's variance of a ball believed nearly at rest
every frame, and with it any chance to see a kick coming), plus the
discrete white acceleration noise of spectral density ``acceleration_psd`` and the odometry's
noise (``odometry_translation_std_fraction`` of the distance walked, ``odometry_turn_std_fraction``
of the turn plus ``odometry_turn_std_floor_rad``).

Each frame's ball sightings (range, bearing) become robot-frame points with covariance
``J cov J^T``. The sighting nearest the prediction (Mahalanobis) is fused when it passes the
chi-square gate at ``gate_probability``. When none passes, the ball may have been kicked since
the last frame: the prediction is made again from the last frame with the velocity's covariance
grown by ``kick_velocity_std_mps`` squared per axis (a velocity jump of that size at the last
frame), and the gate tried again. A sighting that passes it is fused there if the last frame
fused a sighting; if not, the belief had gone unconfirmed, and a jump at the last frame would
make up a velocity to explain how far it drifted since: the filter restarts at the sighting
instead. A sighting still outside is kept as an outlier; when the next frame's sighting agrees
with it (within the gate of their joint covariance, after the robot's motion) and still not
with the filter, the filter restarts there (the ball was moved, or the filter had followed a
false sighting). With ``start_confirm_s`` None, the first sighting starts the filter at rest
with velocity std ``initial_velocity_std_mps``; set (the default), it takes two sightings
that agree: each of a frame's sightings becomes a waiting belief, started as above and predicted
from frame to frame like the belief itself (rolling, the robot's motion) for up to
``start_confirm_s``; the best-scored later sighting within the gate of a waiting belief (the
nearest, by the gate's distance) is fused into it, which starts the belief, so that the start
equals the first sighting's belief after its second; when none agrees, the later frame's
sightings wait in their place. A single false sighting, such as the foot of a goal post at the
image's top edge that the CNN scores just over its threshold, then starts nothing. The two
sightings are taken as independent, though the walk's sway that tilts the camera (a part of
their noise) changes little from one frame to the next. The estimate's ``candidate`` shows
where the best-scored sighting waits, for a head to look at it again. When a belief is lost in
a frame whose sightings it did not take, they wait so too.

A belief left without sightings grows uncertain (the ball rolls on in it, or a ball stopped by a
robot rolls on only in the belief): once its position std (the root of the trace of the
position covariance) exceeds ``lost_std_m``, the ball is lost. The filter forgets it (``known``
False, as before the first sighting; ``last_seen_s`` kept) and the next sightings start it
afresh, so that nobody walks after a belief that has nothing left to do with the ball. So it is
when the belief lay where the camera would have seen it (``in_view``) in frames since its last
fused sighting that would all have missed a ball there with a chance under ``lost_chance``
(each frame's chance to see it from ``detection_chance`` at the believed range). The test takes
the belief's mean for the ball and the frames' misses as independent. They are not beside a
robot: its feet hide the ball, or the CNN takes the two for one, frame after frame. So a ball
believed within ``near_robot_m`` of a robot believed there (``robots``) is seen at most with
``near_robot_detection_chance`` (0 by default: such misses are not counted), and one hidden
behind a robot farther away is lost as soon as one in the open would be.

Our own kicks are known to the robot's motion: a kick's intended velocity (robot frame) given to
a ball believed in front of the feet (``own_kick_reach_m`` ahead, ``own_kick_half_width_m`` to
either side) sets the ball's velocity to that kick's rolling
velocity (``own_kick_rolling_fraction`` of it) with std ``own_kick_std_mps`` on each axis,
forgetting the velocity's correlations. A kick may also leave the ball where it was (blocked by
a robot behind it, or the ball not quite in the kick zone), so the belief without the kick is
kept beside it, predicted alike, until a sighting is fused (into the kicked belief, as any
sighting: a sighting near the feet after a kick is as often something else, such as the
penalty mark the ball has left); when the kicked belief is lost unseen, the ball is believed
where it was, if that belief's position std is still under ``lost_std_m`` (its own misses in
view are not counted: it lies at our feet, where the top camera cannot see). A second kick
before a sighting keeps only its own belief without the kick (the first kick's kicked
belief).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from perception.estimation.gating import chi2_threshold, mahalanobis_squared
from perception.estimation.kalman import joseph_update
from perception.geometry import FloatArray, rot_z
from perception.tracking.checked_inputs import (
    TIME_ROUNDING_S,
    checked_self_pose,
    checked_sightings,
)
from perception.tracking.robot_tracker import constant_velocity_model, sighting_in_field
from perception.types import BallEstimate, BallSighting, SlamEstimate
from perception.validation import (
    check_finite,
    check_in_interval,
    check_instance,
    check_positive,
    check_probability,
    finite_points,
    finite_vector,
)

_OWNER = "BallFilterConfig"
_H = np.hstack([np.eye(2), np.zeros((2, 2))])  # the sightings measure the position
_ORIGIN, _NO_POSE_COV = np.zeros(3), np.zeros((3, 3))  # a sighting in the robot's own frame


@dataclass(frozen=True, kw_only=True)
class BallFilterConfig:
    """Motion model, noise and gating of :class:`BallFilter` (module doc)."""

    # Rolling friction (m/s^2): the simulator's ball (spl_env scene, rolling friction 0.0015)
    # slows by 0.106-0.128 m/s per second at 0.3-1.4 m/s once it rolls.
    deceleration_mps2: float = 0.11
    acceleration_psd: float = 0.05  # white acceleration noise (m^2/s^3) on each axis
    initial_velocity_std_mps: float = 0.5  # a ball first seen is at rest, give or take this
    kick_velocity_std_mps: float = 2.0  # a kick's velocity jump (m/s) per axis
    # chi-square gate (2 dof) of a sighting against the filter: a sighting outside it is taken
    # for a kick, so a genuine one should rarely fall outside (1 in 1000)
    gate_probability: float = 0.999
    # A belief whose position std (m, root of the trace of the position covariance) exceeds
    # this is dropped: the ball is lost. A ball at rest, unseen, gets there after about 3 s.
    lost_std_m: float = 1.0
    # ... and so is one that lay in view in frames since its last fused sighting that would
    # all have missed a ball there with a chance under lost_chance. The chance that the top
    # camera finds a ball in view, by range: (upper bound (m), chance) in ascending order, 0
    # beyond the last (ball_detection_top.json, tuning seeds 0-4: 71 / 80 / 86 % at 0-1 / 1-2
    # / 2-3 m; nearer than 0.6 m the ball leaves the image's bottom).
    detection_chance: tuple[tuple[float, float], ...] = (
        (0.6, 0.0),
        (1.0, 0.7),
        (2.0, 0.8),
        (3.0, 0.86),
    )
    lost_chance: float = 0.01
    # ... but beside a robot (a confirmed robot track within near_robot_m of the ball, centre
    # to centre) the chance is at most near_robot_detection_chance: its feet beside the ball
    # make the CNN miss it, frame after frame. In play the top camera found a ball in view in
    # 48 % of the frames with a robot within 0.5 m, against 80-97 % in the open (rendered
    # goalie, tuning seeds 0-49, and striker, seeds 0-15; benchmarks/ball_detection_near_robots
    # .py). Counted as independent misses, the goalie lost the ball at rest by the kicker's
    # feet before its kick and looked for it elsewhere: with start_confirm_s, shots kept out
    # on the tuning seeds 40 % (the misses counted at the open chance), 44 % (at 0.5), 50 %
    # (not counted, the default; before the head looked at waiting sightings), 52 % without
    # start_confirm_s either way.
    near_robot_m: float = 0.5
    near_robot_detection_chance: float = 0.0
    # A first sighting waits this long (s) for a second that agrees with it before a belief
    # starts (module doc); None: the first sighting starts it. In the rendered striker (tuning
    # seeds 0-15) the false sightings that started beliefs metres off (a goal post's foot at
    # the image's top edge, the boards' bottom edge, scored 0.40-0.58) came alone, and made
    # 60 % of the relative ball error (benchmarks/ball_belief_errors.py, "far_off"); the ball,
    # seen from frame to frame, is believed a frame later. Shorter than the time between two
    # frames, no belief ever starts. The scripted soccer head looks at the waiting sighting
    # (BallEstimate.candidate): without that, and with a ball at rest beside a robot lost by
    # misses, the rendered goalie had kept out 38 % of the shots against 62 % (held-out seeds
    # 100-149); with both and start_at_once_score, 60 %, and 52 % against 46 % on seeds
    # 200-249 (docs/measurements.md)
    start_confirm_s: float | None = 0.3
    # ... except that a sighting the detector scored this or more starts a belief at once (None:
    # every start waits). The false sightings that had started beliefs scored 0.40-0.58. On
    # the tuning seeds (rendered striker 0-15 / goalie 0-49): relative ball error within 3 m
    # 0.044 / 0.068 / 0.055 / 0.056 m and shots kept out 50 / 54 / 52 / 50 % for None / 0.6 /
    # 0.7 / 0.8; in the geometric mode, whose emulated sightings score 1 and are never false,
    # every start waiting had cost 3-6 points of success on tuning seeds 0-99, which any
    # value up to 1 gives back.
    start_at_once_score: float | None = 0.7
    # in view (the provider's in_view): this share of the image's size inside its edges
    view_margin: float = 0.1
    # The walk odometry's noise as the filter takes it (a share of each step's distance and
    # turn, and a floor on the turn's std per frame)
    odometry_translation_std_fraction: float = 0.1
    odometry_turn_std_fraction: float = 0.1
    odometry_turn_std_floor_rad: float = 0.002
    # Our own kick: a ball believed in front of our feet (up to own_kick_reach_m ahead of our
    # centre, own_kick_half_width_m to either side: the Nao's kick zone and a little more) takes
    # the kick's velocity times own_kick_rolling_fraction (the simulator's kicked ball slides,
    # then rolls at 5/7 of the kick's speed: 1.42 of 2.0 m/s measured), give or take
    # own_kick_std_mps.
    own_kick_reach_m: float = 0.3
    own_kick_half_width_m: float = 0.15
    own_kick_rolling_fraction: float = 0.71
    own_kick_std_mps: float = 0.3

    def __post_init__(self) -> None:
        check_positive(_OWNER, "deceleration_mps2", self.deceleration_mps2, allow_zero=True)
        for name in (
            "acceleration_psd",
            "initial_velocity_std_mps",
            "kick_velocity_std_mps",
            "lost_std_m",
            "own_kick_reach_m",
            "own_kick_half_width_m",
            "own_kick_std_mps",
        ):
            check_positive(_OWNER, name, getattr(self, name))
        for name in (
            "odometry_translation_std_fraction",
            "odometry_turn_std_fraction",
            "odometry_turn_std_floor_rad",
        ):
            check_positive(_OWNER, name, getattr(self, name), allow_zero=True)
        check_probability(_OWNER, "gate_probability", self.gate_probability, float_only=True)
        check_in_interval(_OWNER, "view_margin", self.view_margin, 0.0, 0.5, low_inclusive=True)
        check_probability(_OWNER, "lost_chance", self.lost_chance, float_only=True)
        check_positive(_OWNER, "near_robot_m", self.near_robot_m, allow_zero=True)
        check_in_interval(
            _OWNER,
            "near_robot_detection_chance",
            self.near_robot_detection_chance,
            0.0,
            1.0,
            low_inclusive=True,
            high_inclusive=True,
            float_only=True,
        )
        if self.start_confirm_s is not None:
            check_positive(_OWNER, "start_confirm_s", self.start_confirm_s)
        if self.start_at_once_score is not None:
            check_in_interval(
                _OWNER,
                "start_at_once_score",
                self.start_at_once_score,
                0.0,
                1.0,
                high_inclusive=True,
                float_only=True,
            )
        pairs = self.detection_chance
        if not isinstance(pairs, tuple) or not all(
            isinstance(pair, tuple) and len(pair) == 2 for pair in pairs
        ):
            raise TypeError(
                f"{_OWNER}.detection_chance must be a tuple of (upper bound, chance) tuples, "
                f"got {pairs!r}"
            )
        for k, (bound, _) in enumerate(pairs):
            check_finite(_OWNER, f"detection_chance[{k}][0]", bound)
        bounds = [float(bound) for bound, _ in pairs]
        if not bounds or bounds != sorted(set(bounds)) or bounds[0] <= 0:
            raise ValueError(
                f"{_OWNER}.detection_chance must be (upper bound, chance) pairs with positive "
                f"ascending bounds, got {self.detection_chance}"
            )
        for k, (_, chance) in enumerate(self.detection_chance):
            check_in_interval(
                _OWNER,
                f"detection_chance[{k}][1]",
                chance,
                0.0,
                1.0,
                low_inclusive=True,
                high_inclusive=True,
            )
        check_in_interval(
            _OWNER,
            "own_kick_rolling_fraction",
            self.own_kick_rolling_fraction,
            0.0,
            1.0,
            high_inclusive=True,
        )

    def chance_to_see(self, range_m: float, beside_robot: bool = False) -> float:
        """The chance (``detection_chance``) that a ball in view at ``range_m`` (m) is seen; at
        most ``near_robot_detection_chance`` ``beside_robot``."""
        for bound, chance in self.detection_chance:
            if range_m <= bound:
                return min(chance, self.near_robot_detection_chance) if beside_robot else chance
        return 0.0

    @property
    def gate_threshold(self) -> float:
        """Chi-square (2 dof) quantile at ``gate_probability``."""
        return chi2_threshold(self.gate_probability, 2)


def rolling_model(
    state: FloatArray, dt: float, config: BallFilterConfig
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The state (4,) after ``dt`` >= 0 s of rolling in a fixed frame (module doc), with the
    covariance's ``F`` (4, 4) (constant velocity) and white-acceleration ``Q`` (4, 4)."""
    speed = float(math.hypot(state[2], state[3]))
    a = config.deceleration_mps2
    rolling_s = min(dt, speed / a) if a > 0 else dt
    distance = speed * rolling_s - 0.5 * a * rolling_s**2
    factor = max(speed - a * dt, 0.0) / speed if speed > 0 else 1.0
    travel = distance / speed if speed > 0 else dt  # seconds of the current velocity travelled
    predicted = np.array(
        [
            state[0] + travel * state[2],
            state[1] + travel * state[3],
            factor * state[2],
            factor * state[3],
        ]
    )
    F, Q = constant_velocity_model(dt, config.acceleration_psd)  # the covariance's
    return predicted, F, Q


def moved_frame(
    state: FloatArray, odometry: FloatArray, config: BallFilterConfig
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The state (4,) seen from the robot frame after the robot's motion ``odometry`` (3,)
    ``(dx, dy, dθ)`` (in the old frame), with the map's Jacobian ``G`` (4, 4) and the
    odometry's noise ``Q`` (4, 4) (module doc)."""
    dx, dy, dtheta = (float(v) for v in odometry)
    back = rot_z(-dtheta)[:2, :2]
    offset = state[:2] - np.array([dx, dy])
    moved = np.concatenate([back @ offset, back @ state[2:]])
    G = np.zeros((4, 4))
    G[:2, :2] = G[2:, 2:] = back
    turn_std = config.odometry_turn_std_fraction * abs(dtheta) + config.odometry_turn_std_floor_rad
    walk_std = config.odometry_translation_std_fraction * math.hypot(dx, dy)
    turn_jacobian = np.array([[0.0, 1.0], [-1.0, 0.0]]) @ back  # d(back)/d(dθ)
    Q = np.zeros((4, 4))
    Q[:2, :2] = walk_std**2 * np.eye(2)
    position_turn = turn_jacobian @ offset
    velocity_turn = turn_jacobian @ state[2:]
    both = np.concatenate([position_turn, velocity_turn])
    Q += turn_std**2 * np.outer(both, both)
    return moved, G, Q


def position_std(cov: FloatArray) -> float:
    """The position std (m) of a ball state's covariance ``cov`` (4, 4): the root of the trace
    of its position block."""
    return math.sqrt(max(float(np.trace(cov[:2, :2])), 0.0))


def ball_in_field(
    relative: FloatArray, relative_cov: FloatArray, pose: FloatArray, pose_cov: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The ball's field-frame state (4,) and covariance (4, 4) from its robot-frame ``relative``
    (4,) with ``relative_cov`` (4, 4), seen from ``pose`` (3,) with ``pose_cov`` (3, 3) (first
    order; the two independent)."""
    turn = rot_z(pose[2])[:2, :2]
    state = np.concatenate([pose[:2] + turn @ relative[:2], turn @ relative[2:]])
    J_rel = np.zeros((4, 4))
    J_rel[:2, :2] = J_rel[2:, 2:] = turn
    d_turn = np.array([[0.0, -1.0], [1.0, 0.0]]) @ turn  # d(turn)/dθ
    J_pose = np.zeros((4, 3))
    J_pose[:2, :2] = np.eye(2)
    J_pose[:2, 2] = d_turn @ relative[:2]
    J_pose[2:, 2] = d_turn @ relative[2:]
    cov = J_rel @ relative_cov @ J_rel.T + J_pose @ pose_cov @ J_pose.T
    return state, 0.5 * (cov + cov.T)


class BallFilter:
    """The ball's egocentric Kalman filter (module doc); :meth:`update` once per frame."""

    def __init__(self, config: BallFilterConfig | None = None) -> None:
        check_instance("config", config, BallFilterConfig, optional=True)
        self.config = config if config is not None else BallFilterConfig()
        self._gate = self.config.gate_threshold
        self.reset()

    def reset(self) -> None:
        """Forget the ball."""
        self._state = np.zeros(4)
        self._cov = np.eye(4)
        self._known = False
        self._last_seen_s = -math.inf
        self._time_s: float | None = None
        self._outlier: tuple[FloatArray, FloatArray] | None = None
        # beliefs (state, covariance) of sightings awaiting a second, and since when (s)
        self._waiting: list[tuple[FloatArray, FloatArray]] = []
        self._waiting_s = -math.inf
        self._unkicked: tuple[FloatArray, FloatArray] | None = None  # our kick left it be
        self._unseen_chance = 1.0  # that a ball where believed was missed since last seen

    def estimate(self, self_pose: SlamEstimate | tuple[ArrayLike, ArrayLike]) -> BallEstimate:
        """What the filter believes now, placed on the field from ``self_pose`` (a
        :class:`SlamEstimate` or a ``(pose, pose_cov)`` pair, checked as in :meth:`update`)."""
        return self._estimate_at(*checked_self_pose(self_pose))

    def _estimate_at(self, pose: FloatArray, pose_cov: FloatArray) -> BallEstimate:
        """:meth:`estimate` from the checked ``pose`` (3,) and ``pose_cov`` (3, 3)."""
        field_state, field_cov = ball_in_field(self._state, self._cov, pose, pose_cov)
        return BallEstimate(
            state=field_state if self._known else np.zeros(4),
            cov=field_cov if self._known else self._cov.copy(),
            relative=self._state.copy(),
            relative_cov=self._cov.copy(),
            known=self._known,
            last_seen_s=self._last_seen_s,
            candidate=None if self._known or not self._waiting else self._waiting[0][0][:2].copy(),
        )

    def update(
        self,
        time_s: float,
        sightings: Sequence[BallSighting],
        odometry: FloatArray,
        self_pose: SlamEstimate,
        kick_velocity: FloatArray | None = None,
        in_view: Callable[[FloatArray], bool] | None = None,
        robots: ArrayLike | None = None,
    ) -> BallEstimate:
        """Roll on to ``time_s`` (s, not before the last update) and move with the robot's
        ``odometry`` (3,) since the last frame; take our own kick since then (``kick_velocity``
        (2,) m/s, robot frame, zero or None for none); fuse this frame's ``sightings`` (robot
        frame; taken best-scored first, in whatever order given); lose a ball whose belief
        grew too uncertain, or lay ``in_view`` (whether a robot-frame point (2,) shows in this
        frame's image; None: not known) unseen too often, counting no misses beside ``robots``
        (N, 2) (m, robot frame: the robots believed around; None or empty: none known) at the
        default ``near_robot_detection_chance`` (module doc).
        Returns the estimate placed on the field from ``self_pose``.

        Every argument is checked before the filter changes; bad ones raise ValueError or
        TypeError naming them."""
        check_finite("", "time_s", time_s)
        if self._time_s is not None and time_s < self._time_s:
            raise ValueError(f"time_s must not go back: {time_s} after {self._time_s}")
        odometry = finite_vector(odometry, "odometry", 3)
        checked = checked_sightings(sightings, BallSighting)
        best_first = sorted(range(len(checked)), key=lambda k: -float(sightings[k].score))
        checked = [checked[k] for k in best_first]  # a stable sort: equals keep their order
        best_score = float(sightings[best_first[0]].score) if best_first else 0.0
        pose, pose_cov = checked_self_pose(self_pose)
        if in_view is not None and not callable(in_view):
            raise TypeError(f"in_view must be a function of a point (2,) or None, got {in_view!r}")
        robot_points = np.zeros((0, 2))
        # [], () and an empty array: no robot either
        empty = np.size(robots) == 0 if isinstance(robots, np.ndarray) else robots in ([], ())
        if robots is not None and not empty:
            robot_points = finite_points(robots, "robots")
        kick = (
            np.zeros(2)
            if kick_velocity is None
            else finite_vector(kick_velocity, "kick_velocity", 2)
        )
        dt = 0.0 if self._time_s is None else time_s - self._time_s
        confirmed = self._last_seen_s == self._time_s  # the last frame fused a sighting
        before = (self._state, self._cov)
        if self._known and np.any(kick):
            before = self._kicked_by_us(kick)
        if self._known:
            self._state, self._cov = self._predicted(*before, dt, odometry)
            if self._unkicked is not None:
                self._unkicked = self._predicted(*self._unkicked, dt, odometry)
            if self._outlier is not None:
                self._outlier = self._moved_point(self._outlier, odometry)
        elif self._waiting:
            limit = self.config.start_confirm_s
            if limit is not None and time_s - self._waiting_s > limit + TIME_ROUNDING_S:
                self._waiting = []
            self._waiting = [self._predicted(x, P, dt, odometry) for x, P in self._waiting]
        self._time_s = time_s
        measurements = [
            sighting_in_field(_ORIGIN, _NO_POSE_COV, range_m, bearing, cov)
            for range_m, bearing, cov in checked
        ]
        if measurements:
            self._fuse(measurements, time_s, before, dt, odometry, confirmed, best_score)
        else:
            self._outlier = None  # an outlier needs the very next frame's agreement
        if self._last_seen_s == time_s:
            self._unseen_chance = 1.0
        elif self._known and in_view is not None and in_view(self._state[:2].copy()):
            range_m = math.hypot(*self._state[:2])
            gaps = np.hypot(*(robot_points - self._state[:2]).T)
            beside = bool(np.any(gaps < self.config.near_robot_m))
            self._unseen_chance *= 1.0 - self.config.chance_to_see(range_m, beside)
        c = self.config
        if self._known and (
            position_std(self._cov) > c.lost_std_m or self._unseen_chance < c.lost_chance
        ):
            self._lost()
            if not self._known and measurements and c.start_confirm_s is not None:
                self._wait(measurements, time_s)  # none fitted the lost belief
        return self._estimate_at(pose, pose_cov)

    def _lost(self) -> None:
        """The belief grew too uncertain, or went unseen in view: the ball where our last kick
        may have left it, if that is still believable; else forgotten until the next sighting
        (module doc)."""
        unkicked, self._unkicked, self._outlier = self._unkicked, None, None
        self._unseen_chance = 1.0
        if unkicked is not None and position_std(unkicked[1]) <= self.config.lost_std_m:
            self._state, self._cov = unkicked
        else:  # as before the first sighting
            self._known, self._state, self._cov = False, np.zeros(4), np.eye(4)

    def _kicked_by_us(self, kick_velocity: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The state and covariance of the last frame after our kick of ``kick_velocity`` (2,):
        the kick's rolling velocity for a ball within reach, else unchanged."""
        c = self.config
        ahead, aside = self._state[:2]
        if not (0.0 < ahead <= c.own_kick_reach_m and abs(aside) <= c.own_kick_half_width_m):
            return self._state, self._cov
        self._unkicked = (self._state, self._cov)
        state = np.concatenate([self._state[:2], c.own_kick_rolling_fraction * kick_velocity])
        cov = self._cov.copy()
        cov[2:, :] = 0.0
        cov[:, 2:] = 0.0
        cov[2:, 2:] = c.own_kick_std_mps**2 * np.eye(2)
        return state, cov

    def _predicted(
        self, state: FloatArray, cov: FloatArray, dt: float, odometry: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """``state`` (4,) and ``cov`` (4, 4) rolled on by ``dt`` s, then moved with the robot's
        ``odometry`` (3,) (module doc)."""
        state, F, Q = rolling_model(state, dt, self.config)
        cov = F @ cov @ F.T + Q
        state, G, Q_odometry = moved_frame(state, odometry, self.config)
        cov = G @ cov @ G.T + Q_odometry
        return state, 0.5 * (cov + cov.T)

    def _moved_point(
        self, point: tuple[FloatArray, FloatArray], odometry: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """A resting point ``(z (2,), R (2, 2))`` of the last frame seen from this frame."""
        state, G, Q = moved_frame(np.array([*point[0], 0.0, 0.0]), odometry, self.config)
        R = G[:2, :2] @ point[1] @ G[:2, :2].T + Q[:2, :2]
        return state[:2], 0.5 * (R + R.T)

    def _fuse(
        self,
        measurements: list[tuple[FloatArray, FloatArray]],
        time_s: float,
        before: tuple[FloatArray, FloatArray],
        dt: float,
        odometry: FloatArray,
        confirmed: bool,
        best_score: float,
    ) -> None:
        """Fuse the measurement that fits best (module doc); a restart or an outlier else.
        ``before`` is the state and covariance before this frame's prediction; ``confirmed``
        whether the last frame fused a sighting; ``best_score`` the best sighting's score."""
        if not self._known:
            self._confirm_start(measurements, time_s, best_score)
            return
        best = self._nearest(measurements)
        if best is None:  # perhaps kicked since the last frame: a velocity jump then
            kicked_cov = before[1].copy()
            kicked_cov[2:, 2:] += self.config.kick_velocity_std_mps**2 * np.eye(2)
            held = (self._state, self._cov)
            self._state, self._cov = self._predicted(before[0], kicked_cov, dt, odometry)
            best = self._nearest(measurements)
            if best is None:
                self._state, self._cov = held
            elif not confirmed:  # drifted unconfirmed: the sighting outweighs the belief
                self._start(*best, time_s)
                return
        if best is not None:
            z, R = best
            self._state, self._cov = joseph_update(
                self._state, self._cov, z - self._state[:2], _H, R
            )
            self._last_seen_s = time_s
            self._outlier = self._unkicked = None
            return
        z, R = measurements[0]
        if self._outlier is not None and self._agrees(self._outlier, (z, R)):
            self._start(z, R, time_s)
        else:
            self._outlier = (z, R)

    def _confirm_start(
        self, measurements: list[tuple[FloatArray, FloatArray]], time_s: float, best_score: float
    ) -> None:
        """Start a belief from the first of ``measurements`` (``start_confirm_s`` None), or from
        the best-scored of them (they come best first) within the gate of a waiting belief,
        fused into the nearest such, or from the first when ``best_score`` reaches
        ``start_at_once_score``; else they wait (module doc)."""
        c = self.config
        if c.start_confirm_s is None:
            self._start(*measurements[0], time_s)
            return
        for z, R in measurements:
            distances = [
                float(mahalanobis_squared(z - x[:2], P[:2, :2] + R)) for x, P in self._waiting
            ]
            if distances and min(distances) <= self._gate:
                x, P = self._waiting[int(np.argmin(distances))]
                self._start_from(*joseph_update(x, P, z - x[:2], _H, R), time_s)
                return
        if c.start_at_once_score is not None and best_score >= c.start_at_once_score:
            self._start(*measurements[0], time_s)
            return
        self._wait(measurements, time_s)

    def _wait(self, measurements: list[tuple[FloatArray, FloatArray]], time_s: float) -> None:
        """Each of ``measurements`` (best-scored first) waits, from ``time_s``, for a second
        sighting that agrees with it."""
        self._waiting = [self._at_rest(z, R) for z, R in measurements]
        self._waiting_s = time_s

    def _nearest(
        self, measurements: list[tuple[FloatArray, FloatArray]]
    ) -> tuple[FloatArray, FloatArray] | None:
        """The measurement with the least Mahalanobis distance to the prediction, if within the
        gate."""
        P = self._cov[:2, :2]
        distances = [
            float(mahalanobis_squared(z - self._state[:2], P + R)) for z, R in measurements
        ]
        k = int(np.argmin(distances))
        return measurements[k] if distances[k] <= self._gate else None

    def _agrees(self, a: tuple[FloatArray, FloatArray], b: tuple[FloatArray, FloatArray]) -> bool:
        """Whether two robot-frame measurements ``(z, R)`` can show the same resting ball."""
        return float(mahalanobis_squared(a[0] - b[0], a[1] + b[1])) <= self._gate

    def _at_rest(self, z: FloatArray, R: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The state (4,) and covariance (4, 4) of a ball at the measurement ``z`` (2,) with
        covariance ``R``, at rest give or take ``initial_velocity_std_mps``."""
        cov = np.zeros((4, 4))
        cov[:2, :2] = R
        cov[2:, 2:] = self.config.initial_velocity_std_mps**2 * np.eye(2)
        return np.array([z[0], z[1], 0.0, 0.0]), cov

    def _start(self, z: FloatArray, R: FloatArray, time_s: float) -> None:
        """Start (or restart) the filter at the measurement ``z`` (2,) with covariance ``R``."""
        self._start_from(*self._at_rest(z, R), time_s)

    def _start_from(self, state: FloatArray, cov: FloatArray, time_s: float) -> None:
        """Start (or restart) the filter at ``state`` (4,) with ``cov`` (4, 4), seen now."""
        self._state, self._cov = state, cov
        self._known = True
        self._last_seen_s = time_s
        self._outlier = self._unkicked = None
        self._waiting = []
