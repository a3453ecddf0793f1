"""Per-step wall-clock timings reported in ``info["timing"]``."""

from __future__ import annotations

from collections.abc import Iterator, Mapping


class StepTimes(Mapping[str, float]):
    """Seconds spent in each part of a step, read like a dict: ``times["render"]``.

    Two ``StepTimes`` compare equal when they time the same parts: the seconds measure the host
    machine, not the simulated world, so steps that agree in every simulated respect (same seed,
    same actions) compare equal, as Gymnasium's determinism checks expect of ``info``.
    """

    __hash__ = None  # type: ignore[assignment]

    def __init__(self, **seconds: float) -> None:
        self._seconds = dict(seconds)

    def __getitem__(self, part: str) -> float:
        return self._seconds[part]

    def __iter__(self) -> Iterator[str]:
        return iter(self._seconds)

    def __len__(self) -> int:
        return len(self._seconds)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, StepTimes) and self._seconds.keys() == other._seconds.keys()

    def __repr__(self) -> str:
        parts = ", ".join(f"{k}={1000 * v:.2f} ms" for k, v in self._seconds.items())
        return f"StepTimes({parts})"
