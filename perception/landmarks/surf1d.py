"""1-D SURF features of a horizon signal (seed 004 chapter 3; SURF: Bay et al. 2008).

The input is a 1-D signal ``f`` (K,), e.g. the horizon band of
:func:`perception.landmarks.horizon.horizon_band`, positions in samples. SURF searches a
scale space of (x, y, scale) for extrema of the Hessian's determinant; 1-D SURF searches
(x, scale) for extrema of the second derivative, with the seed's simplifications (no
orientation, no sub-sample interpolation, extrema in space only):

- Integral signal ``I`` (K + 1,), ``I[k] = f[0] + ... + f[k - 1]``: a box sum over samples
  ``a .. b - 1`` is ``I[b] - I[a]``, whatever the box's length.
- Second derivative: SURF's Dxx box filter along one axis, three lobes of ``l = L / 3``
  samples weighted +1, -2, +1, centred on a sample, its sum divided by the filter size ``L``.
  For a signal with curvature ``f''`` the response is about ``f'' l**2 / 3``, a
  scale-normalised second derivative, so a signal stretched by 2 gives the same response at
  twice the filter size. A bright blob (a peak) gives a negative response.
- Filter sizes, SURF's scheme: octave ``o = 1, 2, ...`` holds ``intervals + 1`` sizes
  ``L = 3 (2**o (i + 1) + 1)``, ``i = 0 .. intervals``, evaluated every ``2**(o - 1)``
  samples (the octave's sample step). With 3 intervals: 9, 15, 21, 27 (step 1); 15, 27, 39,
  51 (step 2); 27, 51, 75, 99 (step 4); 51, 99, 147, 195 (step 8). A size already in a finer
  octave is evaluated once, at the finer step (as OpenSURF's response layers), leaving 10
  layers for 4 octaves. Responses sit on the samples that are multiples of the step and
  whose filter lies inside the signal, so extraction commutes with shifts of the signal by
  multiples of ``2**(octaves - 1)`` samples. Scale ``s = 1.2 L / 9`` samples (SURF: the 9-tap
  filter approximates a Gaussian of sigma 1.2).
- Detection: a response is a feature when it is a strict extremum among its left and right
  neighbours of the same layer (one step away) and ``|response| > response_threshold``; its
  sign is the Laplacian's sign (+1: a dark blob, -1: a bright one). Scales are not compared:
  the seed wants many weak features rather than few distinctive ones.
- Descriptor: 3 subregions of ``samples_per_subregion`` (5, as SURF's 5 x 5 per subregion)
  Haar samples each, spaced ``s`` apart and centred on the feature, so the window spans
  about ``15 s`` (SURF: 4 subregions, ``20 s``). Each sample is the response of a Haar
  wavelet of size ``2 h``, ``h = max(1, round(s))`` (SURF: 2 s), right half minus left half,
  from the integral signal. Per subregion the sum of the responses and of their absolute
  values: 6 numbers ``(sum dx_1, sum |dx|_1, ..., sum |dx|_3)``, scaled to unit length, so
  the descriptor ignores the signal's offset and gain. Features whose Haar samples reach
  outside the signal, or whose responses are all zero, are dropped.

Everything is computed per layer as (layers, K) arrays at once; no Python loop runs over
samples or features.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.geometry import FloatArray
from perception.validation import InvalidTypeError, check_int, check_positive, finite_vector

SUBREGIONS = 3  # seed 004 §3.2: 3 subregions, a 6-D descriptor
DESCRIPTOR_SIZE = 2 * SUBREGIONS
SURF_SCALE_PER_SIZE = 1.2 / 9.0  # SURF: the 9-sample filter has scale (sigma) 1.2


@dataclass(frozen=True, kw_only=True)
class Surf1dConfig:
    """Scale space, detection threshold and descriptor window of 1-D SURF.

    ``response_threshold`` is in signal units: the response to a bar ``l`` samples wide that
    stands ``c`` above its surroundings is ``-2 c / 3`` at the filter of lobe ``l``. For the
    default 15-row horizon band (:class:`perception.landmarks.horizon.HorizonConfig`), the
    default 30 keeps bars of more than 3 grey levels of contrast.
    """

    octaves: int = 4  # seed 004 §3.2: 4 octaves ...
    intervals: int = 3  # ... of 3 intervals (4 filter sizes per octave)
    response_threshold: float = 30.0  # on |response| (signal units)
    samples_per_subregion: int = 5  # Haar samples per descriptor subregion

    def __post_init__(self) -> None:
        check_int("Surf1dConfig", "octaves", self.octaves, 1)
        check_int("Surf1dConfig", "intervals", self.intervals, 1)
        check_positive(
            "Surf1dConfig", "response_threshold", self.response_threshold, allow_zero=True
        )
        check_int("Surf1dConfig", "samples_per_subregion", self.samples_per_subregion, 1)

    def filter_sizes(self) -> tuple[tuple[int, int], ...]:
        """``(filter size, sample step)`` of each response layer, in samples, finest octave
        first; a size shared by two octaves appears once, with the finer step."""
        layers: dict[int, int] = {}
        for octave in range(1, self.octaves + 1):
            for interval in range(self.intervals + 1):
                size = 3 * (2**octave * (interval + 1) + 1)
                layers.setdefault(size, 2 ** (octave - 1))
        return tuple(layers.items())


@dataclass(frozen=True, eq=False)
class Surf1dFeatures:
    """N features of one signal, ordered by filter size, then position. Arrays read-only.

    - ``index`` (N,) int: sample index of the feature in the signal;
    - ``x`` (N,): its image column (px) (the sample index when no columns were given);
    - ``scale`` (N,): its scale ``s = 1.2 L / 9`` (samples; times the column step for px);
    - ``filter_size`` (N,) int: the filter size ``L`` (samples) it was found at;
    - ``laplacian`` (N,) int8: sign of the second derivative, +1 dark blob, -1 bright blob;
    - ``response`` (N,): the size-normalised second-derivative response (signal units);
    - ``descriptors`` (N, 6): unit-length descriptors.
    """

    index: NDArray[np.int64]
    x: FloatArray
    scale: FloatArray
    filter_size: NDArray[np.int64]
    laplacian: NDArray[np.int8]
    response: FloatArray
    descriptors: FloatArray

    def __len__(self) -> int:
        return len(self.index)


@dataclass(frozen=True, eq=False)
class _Layers:
    """Constants of the L response layers of one config, each an (L,) or (L, S) array."""

    size: NDArray[np.int64]  # filter size L
    step: NDArray[np.int64]  # sample step
    half: NDArray[np.int64]  # (L - 1) / 2: the filter spans centre - half .. centre + half
    lobe: NDArray[np.int64]  # lobe length l = L / 3 (odd)
    scale: FloatArray  # s = 1.2 L / 9
    haar: NDArray[np.int64]  # Haar half size h
    offsets: NDArray[np.int64]  # (L, S): descriptor sample offsets from the centre


@functools.lru_cache(maxsize=16)
def _layers(config: Surf1dConfig) -> _Layers:
    """The response layers of ``config`` (cached: a config is frozen)."""
    size, step = np.array(config.filter_sizes(), dtype=np.int64).T
    scale = SURF_SCALE_PER_SIZE * size
    samples = SUBREGIONS * config.samples_per_subregion
    positions = np.arange(samples) - 0.5 * (samples - 1)  # symmetric about 0, 1 apart
    return _Layers(
        size=size,
        step=step,
        half=(size - 1) // 2,
        lobe=size // 3,
        scale=scale,
        haar=np.maximum(1, np.rint(scale)).astype(np.int64),
        offsets=np.rint(scale[:, None] * positions[None, :]).astype(np.int64),
    )


def extract_features(
    signal: ArrayLike, config: Surf1dConfig, columns: ArrayLike | None = None
) -> Surf1dFeatures:
    """1-D SURF features of ``signal`` (K,) (see the module docstring).

    ``columns`` (K,): the image column (px) of each sample, e.g.
    :attr:`perception.landmarks.horizon.HorizonBand.columns`, giving the features' ``x``;
    None: ``x`` is the sample index.
    """
    if not isinstance(config, Surf1dConfig):
        raise InvalidTypeError(f"config must be a Surf1dConfig, got {type(config).__name__}")
    f = _signal(signal)
    n = len(f)
    x_of = (
        np.arange(n, dtype=np.float64) if columns is None else finite_vector(columns, "columns", n)
    )
    layers = _layers(config)
    integral = np.concatenate(([0.0], np.cumsum(f)))
    response = _responses(integral, layers)
    index = np.arange(n)
    rows = np.arange(len(layers.size))[:, None]
    left = response[rows, np.clip(index - layers.step[:, None], 0, max(n - 1, 0))]
    right = response[rows, np.clip(index + layers.step[:, None], 0, max(n - 1, 0))]
    threshold = config.response_threshold
    peak = (response > left) & (response > right) & (response > threshold)
    trough = (response < left) & (response < right) & (response < -threshold)
    layer, centre, descriptors = _describe(integral, layers, *np.nonzero(peak | trough))
    strength = response[layer, centre]
    features = Surf1dFeatures(
        index=centre.astype(np.int64),
        x=x_of[centre],
        scale=layers.scale[layer],
        filter_size=layers.size[layer],
        laplacian=np.sign(strength).astype(np.int8),
        response=strength,
        descriptors=descriptors,
    )
    for array in vars(features).values():
        array.flags.writeable = False
    return features


def _signal(signal: ArrayLike) -> FloatArray:
    """``signal`` as a new finite float64 (K,) array; errors name the argument."""
    try:
        f = np.array(signal, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InvalidTypeError(f"signal must be a 1-D array of numbers, got {signal!r}") from error
    if f.ndim != 1:
        raise ValueError(f"signal must be 1-D (K,), got shape {f.shape}")
    if not np.isfinite(f).all():
        bad = np.flatnonzero(~np.isfinite(f)).tolist()
        raise ValueError(f"signal must be finite, got NaN or infinity at samples {bad}")
    return f


def _responses(integral: FloatArray, layers: _Layers) -> FloatArray:
    """(L, K) size-normalised box second derivative of every layer at every sample; NaN
    off the layer's sample grid and where the filter leaves the signal."""
    n = len(integral) - 1
    centre = np.arange(n)[None, :]
    half, lobe = layers.half[:, None], layers.lobe[:, None]
    on_grid = (centre - half >= 0) & (centre + half < n) & (centre % layers.step[:, None] == 0)
    total = integral[np.clip(centre + half + 1, 0, n)] - integral[np.clip(centre - half, 0, n)]
    middle = (
        integral[np.clip(centre + (lobe + 1) // 2, 0, n)]
        - integral[np.clip(centre - (lobe - 1) // 2, 0, n)]
    )  # +1 on all three lobes, then -3 on the middle one: +1, -2, +1
    return np.where(on_grid, (total - 3.0 * middle) / layers.size[:, None], np.nan)


def _describe(
    integral: FloatArray, layers: _Layers, layer: NDArray[np.intp], centre: NDArray[np.intp]
) -> tuple[NDArray[np.intp], NDArray[np.intp], FloatArray]:
    """The candidates at ``centre`` (F,) on ``layer`` (F,) that keep a descriptor: their layers,
    centres and unit descriptors (F', 6). Dropped: Haar samples outside the signal, or all
    Haar responses zero."""
    n = len(integral) - 1
    haar = layers.haar[layer]
    samples = centre[:, None] + layers.offsets[layer]  # (F, S)
    inside = (samples[:, 0] - haar >= 0) & (samples[:, -1] + haar <= n)
    layer, centre, samples, h = layer[inside], centre[inside], samples[inside], haar[inside, None]
    dx = integral[samples + h] - 2.0 * integral[samples] + integral[samples - h]
    per_region = dx.reshape(len(centre), SUBREGIONS, samples.shape[1] // SUBREGIONS)
    sums = np.stack([per_region.sum(axis=2), np.abs(per_region).sum(axis=2)], axis=2)
    descriptors = sums.reshape(len(centre), DESCRIPTOR_SIZE)
    norm = np.linalg.norm(descriptors, axis=1)
    keep = norm > 0.0
    return layer[keep], centre[keep], descriptors[keep] / norm[keep, None]
