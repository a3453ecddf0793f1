"""Emulators for the geometric camera mode: they deliver a perception representation (e.g. the
pole sightings, :mod:`spl_env.sensors.emulation.poles`) from the true camera pose plus fitted
noise, without rendering; :mod:`~spl_env.sensors.emulation.registry` picks those the env's
perception config needs, and the sensor rig hands them to the pipeline in place of its
providers."""
