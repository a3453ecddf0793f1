"""``SPL/LookAround-v0``: stand still and look around so that EKF SLAM localises the robot."""

from __future__ import annotations

from dataclasses import dataclass, field

from spl_env.config import EnvConfig
from spl_env.envs.core import SplEnv
from spl_env.tasks.head_control import HeadControlTaskConfig
from spl_env.tasks.look_around import LookAroundTask


@dataclass(frozen=True, kw_only=True)
class LookAroundConfig(EnvConfig):
    """:class:`spl_env.config.EnvConfig` with the look-around task."""

    task: HeadControlTaskConfig = field(default_factory=HeadControlTaskConfig)


class LookAroundEnv(SplEnv):
    """Stand and look around: the simplest head-control task, on the same core as
    ``SPL/ActiveVision-v0``.

    Our Nao stands at a random pose inside the field (1 m from the lines) and never walks; four
    other robots walk about. The **action**, **observation**, **reward**, **info**, camera modes
    and configuration are those of ``SPL/ActiveVision-v0``
    (:class:`spl_env.envs.active_vision.ActiveVisionEnv`), without its body keywords
    (``body_behaviour``, ``square_side_m``). Episodes last ``episode_s`` (60 s).

    Version history: v0, first release.
    """

    task_class = LookAroundTask
    config_class = LookAroundConfig
