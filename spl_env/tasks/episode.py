"""What every task's config has: the episode's length."""

from __future__ import annotations

from dataclasses import dataclass

from perception.validation import check_positive


@dataclass(frozen=True, kw_only=True)
class EpisodeConfig:
    """The episode length; an env truncates after ``episode_s / control_dt_s`` steps."""

    episode_s: float = 60.0  # episode length (s)

    def __post_init__(self) -> None:
        check_positive(type(self).__name__, "episode_s", self.episode_s)
