"""Pictures of the crane for ``CraneAntiSway-v0``'s ``render()``, drawn with numpy only (no
display, no extra dependency): a top view (the X-Y plane of the rails, with the trolley, the
payload's shadow and the target) beside a side view (the X-Z plane: trolley, rope, payload).

Coordinates: ``x`` along the rail [m], ``y`` across it [m], ``z`` down from the rail [m]. The
payload is drawn where the model's ``payload`` property puts it (no geometry is recomputed
here).
"""

from __future__ import annotations

import numpy as np

#: Image size (height, width) in pixels: two square panels side by side.
SIZE = (300, 600)
#: Workspace drawn [m]: x and y ranges of the top view, z range of the side view.
X_RANGE = (-0.05, 0.65)
Y_RANGE = (-0.05, 0.75)
Z_RANGE = (-0.05, 0.75)

_BG = np.array([250, 250, 250], dtype=np.uint8)
_RAIL = np.array([180, 180, 180], dtype=np.uint8)
_TROLLEY = np.array([40, 90, 200], dtype=np.uint8)
_ROPE = np.array([60, 60, 60], dtype=np.uint8)
_PAYLOAD = np.array([220, 60, 40], dtype=np.uint8)
_TARGET = np.array([40, 160, 60], dtype=np.uint8)


def _to_px(v: float, rng: tuple, n: int) -> int:
    return int(round((v - rng[0]) / (rng[1] - rng[0]) * (n - 1)))


def _disc(img: np.ndarray, r: int, c: int, rad: int, color: np.ndarray) -> None:
    h, w, _ = img.shape
    rr, cc = np.ogrid[:h, :w]
    img[(rr - r) ** 2 + (cc - c) ** 2 <= rad * rad] = color


def _line(img: np.ndarray, r0: int, c0: int, r1: int, c1: int, color: np.ndarray) -> None:
    n = max(abs(r1 - r0), abs(c1 - c0), 1) + 1
    rs = np.clip(np.round(np.linspace(r0, r1, n)).astype(int), 0, img.shape[0] - 1)
    cs = np.clip(np.round(np.linspace(c0, c1, n)).astype(int), 0, img.shape[1] - 1)
    img[rs, cs] = color


def frame(state: np.ndarray, payload: np.ndarray, target: np.ndarray) -> np.ndarray:
    """An RGB image ``(300, 600, 3)`` uint8 of the crane in ``state`` (the model's 10 values:
    ``x, y, L, alpha, beta`` and their rates) with the payload at ``payload`` ``(x, y, z)``
    [m] and the target ``(x*, y*)`` [m]."""
    h, w = SIZE
    img = np.empty((h, w, 3), dtype=np.uint8)
    img[:] = _BG
    half = w // 2
    top = img[:, :half]
    side = img[:, half:]
    # top view: rows are y (down the image), columns x
    for y_rail in (Y_RANGE[0] + 0.03, Y_RANGE[1] - 0.03):
        r = _to_px(y_rail, Y_RANGE, h)
        _line(top, r, 0, r, half - 1, _RAIL)
    x, y = float(state[0]), float(state[1])
    tr, tc = _to_px(y, Y_RANGE, h), _to_px(x, X_RANGE, half)
    top[max(tr - 6, 0) : tr + 7, max(tc - 6, 0) : tc + 7] = _TROLLEY
    pr, pc = _to_px(float(payload[1]), Y_RANGE, h), _to_px(float(payload[0]), X_RANGE, half)
    _line(top, tr, tc, pr, pc, _ROPE)
    _disc(top, pr, pc, 4, _PAYLOAD)
    gr, gc = _to_px(float(target[1]), Y_RANGE, h), _to_px(float(target[0]), X_RANGE, half)
    _line(top, gr - 6, gc - 6, gr + 6, gc + 6, _TARGET)
    _line(top, gr - 6, gc + 6, gr + 6, gc - 6, _TARGET)
    # side view: rows are z (down), columns x; the rail at z = 0
    r0 = _to_px(0.0, Z_RANGE, h)
    _line(side, r0, 0, r0, half - 1, _RAIL)
    sc = _to_px(x, X_RANGE, half)
    side[max(r0 - 6, 0) : r0 + 7, max(sc - 8, 0) : sc + 9] = _TROLLEY
    zr, zc = _to_px(float(payload[2]), Z_RANGE, h), _to_px(float(payload[0]), X_RANGE, half)
    _line(side, r0, sc, zr, zc, _ROPE)
    _disc(side, zr, zc, 5, _PAYLOAD)
    gc = _to_px(float(target[0]), X_RANGE, half)
    _line(side, h - 12, gc - 6, h - 1, gc, _TARGET)
    _line(side, h - 12, gc + 6, h - 1, gc, _TARGET)
    img[:, half - 1] = _RAIL
    return img


class Window:
    """``render_mode="human"``: the frames shown in a matplotlib window (matplotlib is imported
    only here; without it a clear ``ImportError`` says what to install)."""

    def __init__(self, fps: float) -> None:
        try:
            import matplotlib.pyplot as plt
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError(
                'render_mode="human" needs matplotlib (pip install matplotlib); '
                'render_mode="rgb_array" needs nothing more'
            ) from e
        self._plt = plt
        self._fig, ax = plt.subplots(figsize=(8, 4))
        ax.set_axis_off()
        self._im = ax.imshow(np.zeros((*SIZE, 3), dtype=np.uint8))
        self._pause = 1.0 / fps

    def show(self, img: np.ndarray) -> None:
        self._im.set_data(img)
        self._fig.canvas.draw_idle()
        self._plt.pause(self._pause)

    def close(self) -> None:
        self._plt.close(self._fig)
