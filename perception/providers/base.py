"""The provider interface and what every provider may be built from."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, ClassVar

from perception.field.dimensions import FieldDimensions
from perception.field.field_map import FieldMap, shared_field_map
from perception.representations import Prior
from perception.types import CameraModel, PoleCode, PoleGeometry

if TYPE_CHECKING:
    from perception.vision.cnn_detector import CnnDetectorConfig, CnnPoleDetector


PREVIOUS = "previous_"  # key prefix of the representations a provider reads one frame late


class Provider(ABC):
    """Computes one representation per frame.

    ``provides`` names the representation; ``requires`` the sensor inputs (fields of
    :class:`perception.types.SensorFrame`) and representations :meth:`update` reads;
    ``requires_previous`` representations it reads as they were after the previous frame
    (keys :data:`PREVIOUS` + name, None on an episode's first frame): a loop such as a pose
    filter reading a recogniser that reads the pose runs one frame apart, without a cycle.
    """

    provides: ClassVar[str]
    requires: ClassVar[tuple[str, ...]]
    requires_previous: ClassVar[tuple[str, ...]] = ()

    def reset(self, prior: Prior) -> None:  # noqa: B027  (stateless providers keep nothing)
        """Start an episode from ``prior``; stateless providers need not override this."""

    @abstractmethod
    def update(self, inputs: Mapping[str, Any], time_s: float) -> Any:
        """This frame's representation from ``inputs`` (one entry per name in ``requires``)
        at time ``time_s`` (s)."""


class PerceptionContext:
    """What providers are built from: the robot's camera and the scene's known landmarks.

    ``camera`` is the camera's intrinsics, None for a robot without one; ``codes`` (L,) the
    pole colour codes with their landmark ids; ``pole`` the pole geometry; ``field`` the SPL
    field's dimensions (the map of :attr:`field_map`). Expensive shared parts (the CNN) are
    built once per context and shared by every provider that reads them (:meth:`cnn_detector`).
    """

    def __init__(
        self,
        camera: CameraModel | None,
        codes: Sequence[PoleCode],
        pole: PoleGeometry,
        field: FieldDimensions | None = None,
    ) -> None:
        self.camera = camera
        self.codes = tuple(codes)
        self.pole = pole
        self.field = field if field is not None else FieldDimensions()
        self._cnn: dict[CnnDetectorConfig, CnnPoleDetector] = {}

    @property
    def field_map(self) -> FieldMap:
        """The map of the field's features (:class:`perception.field.field_map.FieldMap`),
        shared with every context of the same field (:func:`shared_field_map`)."""
        return shared_field_map(self.field)

    def require_camera(self, reader: str) -> CameraModel:
        """The camera's intrinsics for the provider ``reader``; ValueError without a camera."""
        if self.camera is None:
            raise ValueError(f"{reader} reads camera images, but this robot has no camera")
        return self.camera

    def cnn_detector(self, config: CnnDetectorConfig) -> CnnPoleDetector:
        """The CNN detector for ``config``, loaded on first use and then shared."""
        if config not in self._cnn:
            from perception.vision.cnn_detector import CnnPoleDetector  # loads torch

            self._cnn[config] = CnnPoleDetector(
                config, self.require_camera("the CNN detector"), self.codes, self.pole
            )
        return self._cnn[config]
