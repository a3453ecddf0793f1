"""Regenerate the poster textures shipped in ``spl_env/assets/posters``.

Run ``python -m spl_env.assets.make_posters``. Two sets, each drawn from a fixed seed so the
shipped files are reproducible byte for byte:

- ``poster_NN.png`` (the ``"classic"`` set): 64 x 64 procedural clutter (stripes, blocks, discs
  and bars of text-like marks on a tinted ground). Mostly horizontal structure: a level camera's
  horizon row crosses few edges on some of them.
- ``textured_NN.png`` (the ``"textured"`` set, 40 of them): 128 x 128 clutter built to be seen
  along a row:
  upright bars, blocks and columns of marks of many widths and contrasts, the scale-rich texture
  natural landmarks on the horizon need (seed 004 ch. 3-5; an office or a hall has it).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

SIZE_PX = 64
TEXTURED_SIZE_PX = 128
N_POSTERS = 12
N_TEXTURED = 40  # more than the 20 panels: each panel its own (spl_env.scenes.spl_field)


def draw_poster(rng: np.random.Generator) -> np.ndarray:
    """One (64, 64, 3) uint8 BGR poster."""
    img = np.empty((SIZE_PX, SIZE_PX, 3), np.uint8)
    img[:] = rng.integers(40, 230, size=3)
    for _ in range(int(rng.integers(3, 9))):
        colour = tuple(int(c) for c in rng.integers(0, 256, size=3))
        kind = int(rng.integers(4))
        a = rng.integers(0, SIZE_PX, size=2)
        b = rng.integers(0, SIZE_PX, size=2)
        if kind == 0:
            cv2.rectangle(img, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])), colour, -1)
        elif kind == 1:
            cv2.circle(img, (int(a[0]), int(a[1])), int(rng.integers(4, 20)), colour, -1)
        elif kind == 2:
            for row in range(int(a[1]) % 16, SIZE_PX, 8):
                cv2.line(img, (0, row), (SIZE_PX - 1, row), colour, 2)
        else:
            for row in range(8, SIZE_PX - 4, 10):
                x = 4
                while x < SIZE_PX - 8:
                    w = int(rng.integers(2, 7))
                    cv2.rectangle(img, (x, row), (x + w, row + 4), colour, -1)
                    x += w + 2
    return img


def draw_textured_poster(rng: np.random.Generator) -> np.ndarray:
    """One (128, 128, 3) uint8 BGR poster with upright structure at every scale."""
    n = TEXTURED_SIZE_PX
    img = np.empty((n, n, 3), np.uint8)
    img[:] = rng.integers(40, 230, size=3)
    x = 0
    while x < n:  # upright bars of varied widths and contrasts across the whole poster
        width = int(rng.integers(2, 24))
        if rng.random() < 0.6:
            colour = tuple(int(c) for c in rng.integers(0, 256, size=3))
            top, bottom = sorted(int(v) for v in rng.integers(0, n, size=2))
            cv2.rectangle(
                img, (x, min(top, n // 4)), (x + width, max(bottom, 3 * n // 4)), colour, -1
            )
        x += width + int(rng.integers(0, 10))
    for _ in range(int(rng.integers(4, 10))):  # blocks and discs over them
        colour = tuple(int(c) for c in rng.integers(0, 256, size=3))
        a = rng.integers(0, n, size=2)
        if rng.random() < 0.5:
            b = a + rng.integers(4, 40, size=2)
            cv2.rectangle(img, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])), colour, -1)
        else:
            cv2.circle(img, (int(a[0]), int(a[1])), int(rng.integers(3, 18)), colour, -1)
    return img


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "posters")
    parser.add_argument("--seed", type=int, default=2025)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(args.seed)
    for i in range(N_POSTERS):
        cv2.imwrite(str(args.out / f"poster_{i:02d}.png"), draw_poster(rng))
    for i in range(N_TEXTURED):  # after the classic set: its draws stay as they were
        cv2.imwrite(str(args.out / f"textured_{i:02d}.png"), draw_textured_poster(rng))
    print(f"wrote {N_POSTERS + N_TEXTURED} posters to {args.out}")


if __name__ == "__main__":
    main()
