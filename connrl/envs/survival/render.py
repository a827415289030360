"""Pictures of a survival state (``render_mode="rgb_array"``)."""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np

from connrl.envs.survival.world import GRID_SIZE, OBSTACLES

# -------------------------------------------------------------------------------------------- rgb render
_CELL = 20
_COLORS = {
    "floor": (242, 238, 226),
    "line": (222, 216, 200),
    "obstacle": (70, 74, 86),
    "food": (226, 160, 20),
    "enemy": (200, 30, 40),
    "agent": (30, 90, 220),
    "text": (25, 25, 25),
    "bar_bg": (215, 215, 215),
    "panel": (255, 255, 255),
}


@lru_cache(maxsize=1)
def _glyphs() -> tuple[dict[str, np.ndarray], int, int]:
    """Alpha masks of printable ASCII in a monospace font, rendered once with matplotlib's Agg."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    chars = "".join(chr(i) for i in range(32, 127))
    cw, ch, dpi = 8, 15, 100
    fig = Figure(figsize=(cw * len(chars) / dpi, ch / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    for i, x in enumerate(chars):
        fig.text(
            i * cw / (cw * len(chars)), 4 / ch, x, family="DejaVu Sans Mono", fontsize=9.5, color="black"
        )
    canvas.draw()
    alpha = 255 - np.asarray(canvas.buffer_rgba())[:, :, 0].astype(np.int16)
    masks = {x: (alpha[:, i * cw : (i + 1) * cw] / 255.0).astype(np.float32) for i, x in enumerate(chars)}
    return masks, cw, ch


def _draw_text(img: np.ndarray, text: str, row: int, col: int, color=(25, 25, 25)) -> None:
    masks, cw, ch = _glyphs()
    for i, x in enumerate(text):
        m = masks.get(x)
        c0 = col + i * cw
        if m is None or c0 + cw > img.shape[1]:
            continue
        region = img[row : row + ch, c0 : c0 + cw].astype(np.float32)
        img[row : row + ch, c0 : c0 + cw] = (
            region * (1 - m[..., None]) + np.array(color) * m[..., None]
        ).astype(np.uint8)


@lru_cache(maxsize=1)
def _shape_masks() -> dict[str, np.ndarray]:
    """Per-cell masks: food = small disc, enemy = diamond, agent = disc."""
    y, x = np.mgrid[0:_CELL, 0:_CELL] + 0.5 - _CELL / 2
    return {
        "food": (x**2 + y**2) <= (0.28 * _CELL) ** 2,
        "enemy": (np.abs(x) + np.abs(y)) <= 0.47 * _CELL,
        "agent": (x**2 + y**2) <= (0.45 * _CELL) ** 2,
        "arrow": (y <= 0.22 * _CELL) & (np.abs(x) <= (y + 0.36 * _CELL) * 0.5),  # points north
    }


@lru_cache(maxsize=1)
def _background() -> np.ndarray:
    g = GRID_SIZE * _CELL
    margin, panel = 8, 64
    img = np.full((g + 2 * margin + panel, g + 2 * margin, 3), _COLORS["panel"], dtype=np.uint8)
    board = np.full((g, g, 3), _COLORS["floor"], dtype=np.uint8)
    board[::_CELL, :] = _COLORS["line"]
    board[:, ::_CELL] = _COLORS["line"]
    for r, c in np.argwhere(OBSTACLES):
        board[r * _CELL : (r + 1) * _CELL, c * _CELL : (c + 1) * _CELL] = _COLORS["obstacle"]
    img[margin : margin + g, margin : margin + g] = board
    # legend (last line of the panel)
    legend_row = margin + g + 42
    col = margin
    masks = _shape_masks()
    for name, label in (
        ("agent", "agent (I)"),
        ("enemy", "enemy (E)"),
        ("food", "food ($)"),
        ("obstacle", "obstacle (O)"),
    ):
        cell = img[legend_row - 2 : legend_row - 2 + _CELL, col : col + _CELL]
        if name == "obstacle":
            cell[:] = _COLORS["obstacle"]
        else:
            cell[masks[name]] = _COLORS[name]
        _draw_text(img, label, legend_row + 1, col + _CELL + 4)
        col += _CELL + 4 + 8 * len(label) + 16
    return img


def render_rgb(state: dict[str, Any], action_representation: str = "global") -> np.ndarray:
    """Picture of a state (from :meth:`SurvivalEnv.get_state`), in the spirit of thesis Fig. 4.1."""
    img = _background().copy()
    margin, g = 8, GRID_SIZE * _CELL
    masks = _shape_masks()

    def paint(r, c, mask, color):
        cell = img[
            margin + r * _CELL : margin + (r + 1) * _CELL, margin + c * _CELL : margin + (c + 1) * _CELL
        ]
        cell[mask] = color

    for r, c in np.argwhere(state["food"]):
        paint(r, c, masks["food"], _COLORS["food"])
    ar, ac = state["agent"]
    paint(ar, ac, masks["agent"], _COLORS["agent"])
    if action_representation == "local" or state.get("prev_action", -1) >= 0:
        heading = state["orientation"] if action_representation == "local" else state["prev_action"]
        paint(ar, ac, np.rot90(masks["arrow"], -heading), (255, 255, 255))  # arrow: facing / last move
    for r, c in state["enemies"]:
        paint(r, c, masks["enemy"], _COLORS["enemy"])
    if state.get("outcome") == "killed":
        cell = img[
            margin + ar * _CELL : margin + (ar + 1) * _CELL, margin + ac * _CELL : margin + (ac + 1) * _CELL
        ]
        d = np.arange(_CELL)
        for off in (-1, 0, 1):
            cell[d, np.clip(d + off, 0, _CELL - 1)] = (0, 0, 0)
            cell[d, np.clip(_CELL - 1 - d + off, 0, _CELL - 1)] = (0, 0, 0)
    # energy bar: 4 px per unit, a tick every 15 units (one food)
    energy = int(state["energy"])
    top = margin + g + 8
    _draw_text(img, f"energy {energy:3d}", top, margin)
    x0, width = margin + 96, g - 96
    img[top + 1 : top + 13, x0 : x0 + width] = _COLORS["bar_bg"]
    fill = min(width, 4 * max(energy, 0))
    bar_color = (200, 40, 40) if energy <= 10 else (230, 160, 20) if energy <= 25 else (40, 160, 70)
    img[top + 1 : top + 13, x0 : x0 + fill] = bar_color
    img[top + 1 : top + 13, x0 : x0 + width : 60] = (255, 255, 255)
    eaten, left = int(state["food_eaten"]), int(np.sum(state["food"]))
    status = f"food {eaten}/{eaten + left}   step {int(state['steps'])}"
    if state.get("outcome"):
        status += f"   [{state['outcome']}]"
    _draw_text(img, status, top + 17, margin)
    return img


