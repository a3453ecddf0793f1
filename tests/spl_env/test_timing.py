"""StepTimes reads like a dict and compares by the parts it times."""

from __future__ import annotations

from spl_env.timing import StepTimes


def test_step_times_mapping_and_equality() -> None:
    a = StepTimes(physics=0.001, render=0.02)
    assert a["render"] == 0.02 and dict(a) == {"physics": 0.001, "render": 0.02}
    assert sum(a.values()) == 0.021
    assert a == StepTimes(physics=0.5, render=0.7)  # other seconds, same parts
    assert a != StepTimes(physics=0.001)
    assert a != {"physics": 0.001, "render": 0.02}
