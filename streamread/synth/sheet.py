"""Contact sheet: a grid of random renders, so anyone can look at what the renderer makes."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from streamread.synth.scene import render_still


def contact_sheet(count: int = 24, seed: int = 0, columns: int = 6, tile_wh: tuple[int, int] = (320, 240),
                  apparatus: str | None = None, annotate: bool = True) -> np.ndarray:
    """``count`` renders (seeds ``seed .. seed+count-1``) in a grid, each captioned with its truth."""
    if count < 1 or columns < 1:
        raise ValueError(f"contact sheet: expected count and columns >= 1, got {count}, {columns}")
    tw, th = tile_wh
    tiles = []
    for s in range(seed, seed + count):
        image, truth = render_still(s, apparatus)
        sx, sy = tw / image.shape[1], th / image.shape[0]
        scale = min(sx, sy)
        small = cv2.resize(image, (int(image.shape[1] * scale), int(image.shape[0] * scale)), interpolation=cv2.INTER_AREA)
        tile = np.full((th, tw, 3), 255, np.uint8)
        tile[: small.shape[0], : small.shape[1]] = small
        if annotate:
            caption = f"seed {s}: {truth.apparatus} {truth.level_ml:.2f} ml"
            cv2.rectangle(tile, (0, th - 18), (tw, th), (255, 255, 255), -1)
            cv2.putText(tile, caption, (4, th - 5), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (0, 0, 0), 1, cv2.LINE_AA)
        tiles.append(tile)
    while len(tiles) % columns:
        tiles.append(np.full((th, tw, 3), 255, np.uint8))
    rows = [np.hstack(tiles[i: i + columns]) for i in range(0, len(tiles), columns)]
    return np.vstack(rows)


def write_contact_sheet(path: Path, **kwargs: object) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(path), contact_sheet(**kwargs)):  # type: ignore[arg-type]
        raise OSError(f"could not write {path}")
    return path
