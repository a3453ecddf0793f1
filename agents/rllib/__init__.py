"""Ray RLlib training of the SPL envs (the ``ray`` extra: ``pip install -e ".[ray]"``).

:mod:`agents.rllib.envs` builds the envs as RLlib wants them (registered env creators, flat
observations); :mod:`agents.rllib.training` connects to Ray (this machine, or a cluster by its
address) and holds the PPO config and the training loop that ``examples/rllib_striker.py`` and
``examples/rllib_team.py`` share.
"""

import importlib.util


def require_ray() -> None:
    """End the program with the command that installs Ray RLlib when it is missing: an
    example's (or benchmark's) first call, before it imports the modules that need Ray."""
    if importlib.util.find_spec("ray") is None:
        raise SystemExit('this program needs Ray RLlib: pip install -c constraints.txt -e ".[ray]"')
