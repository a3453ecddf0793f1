"""The example scripts run end to end (tiny settings) and print what they promise."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_compare_front_ends(capsys: pytest.CaptureFixture[str]) -> None:
    load("compare_front_ends").main(["--episode-s", "1.0"])
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == ["colour", "cnn"]
    assert all("robot" in line and "odometry alone" in line for line in lines)


def test_ppo_head_control(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["--timesteps", "64", "--episode-s", "2.0", "--eval-episodes", "1"]
    load("ppo_head_control").main(argv)
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == ["ppo", "head"]
