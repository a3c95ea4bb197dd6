"""What a student saw: the image sources of an observation drawn as a panel beside a video.

An image policy reads its camera views as columns of one flat observation; pulling them back
out (by :func:`retarget.learn.columns.image_inputs`) and tiling them shows, frame by frame,
what the network was given — augmentation included, at the resolution it reads.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from retarget.learn.columns import ImageInput


def tile_views(views: np.ndarray, columns: int = 2) -> np.ndarray:
    """``(C, H, W)`` values in [0, 1] -> one grayscale mosaic ``(rows*H + gaps, ...)`` uint8,
    with a 1-pixel dark gap between views."""
    c, h, w = views.shape
    columns = max(1, min(columns, c))
    rows = -(-c // columns)
    out = np.full((rows * (h + 1) - 1, columns * (w + 1) - 1), 24, dtype=np.uint8)
    for k in range(c):
        r, q = divmod(k, columns)
        out[r * (h + 1) : r * (h + 1) + h, q * (w + 1) : q * (w + 1) + w] = np.clip(
            views[k] * 255.0, 0, 255
        ).astype(np.uint8)
    return out


def image_panel(obs: np.ndarray, inputs: Sequence[ImageInput], height: int) -> np.ndarray:
    """RGB panel ``(height, W, 3)`` of every image source in one observation row ``obs``
    (``(D,)``), scaled up by whole pixels (nearest) to fill ``height``, sources stacked."""
    mosaics = [tile_views(obs[i.start : i.start + i.size].reshape(i.shape)) for i in inputs]
    total = sum(m.shape[0] for m in mosaics) + 2 * (len(mosaics) - 1)
    scale = max(1, height // max(total, 1))
    width = max(m.shape[1] for m in mosaics) * scale
    panel = np.full((height, width), 16, dtype=np.uint8)
    top = 0
    for m in mosaics:
        big = np.kron(m, np.ones((scale, scale), dtype=np.uint8))[: height - top]
        panel[top : top + big.shape[0], : big.shape[1]] = big
        top += big.shape[0] + 2 * scale
    return np.repeat(panel[..., None], 3, axis=-1)
