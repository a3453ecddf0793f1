"""Regenerate the poster textures shipped in ``spl_env/assets/posters``.

Run ``python -m spl_env.assets.make_posters``. Each poster is a 64 x 64 PNG of procedural clutter
(stripes, blocks, discs and bars of text-like marks on a tinted ground), drawn from a fixed seed
so the shipped files are reproducible byte for byte.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

SIZE_PX = 64
N_POSTERS = 12


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "posters")
    parser.add_argument("--seed", type=int, default=2025)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(args.seed)
    for i in range(N_POSTERS):
        cv2.imwrite(str(args.out / f"poster_{i:02d}.png"), draw_poster(rng))
    print(f"wrote {N_POSTERS} posters to {args.out}")


if __name__ == "__main__":
    main()
