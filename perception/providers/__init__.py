"""Providers: one per representation, run by :class:`perception.pipeline.PerceptionPipeline`.

Each provider declares the sensor inputs and representations it ``requires`` and the one it
``provides`` (names in :mod:`perception.representations`), is ``reset`` with the episode's
prior and ``update``-d once per frame. Oracle providers (:mod:`perception.providers.oracles`)
read the ground truth and add configured noise; they are chosen by name, never by default.
"""

from perception.providers.base import PerceptionContext, Provider

__all__ = ["PerceptionContext", "Provider"]
