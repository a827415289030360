"""Pictures of the robot world: layout, robot, sonar rays, solution paths, Fig. 5.3, and a live viewer."""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np

from connrl.envs.robot.constants import N_RAYS, RAY_STEP_DEG, ROBOT_RADIUS
from connrl.envs.robot.layout import Layout
from connrl.envs.robot.sim import Reading, RobotSim
from connrl.storage import atomic_write_bytes

# ---------------------------------------------------------------------------------------------------
# Rendering (matplotlib Agg, no pyplot state; works headless)
_ROOM_COLOURS = ("#f3efe4", "#e8eef3", "#eef3e8", "#f3e8ee")


def draw_layout(ax, layout: Layout, *, labels: bool = True, locations: bool = False) -> None:
    """Draw rooms, walls, doorways, obstacles, charger and light on a matplotlib Axes."""
    from matplotlib.patches import Circle, Rectangle

    for i, (name, (x0, y0, x1, y1)) in enumerate(layout.rooms.items()):
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor=_ROOM_COLOURS[i % 4], edgecolor="none"))
        if labels:
            ax.text(x1 - 8, y1 - 8, name, ha="right", va="top", fontsize=14, color="#777", weight="bold")
    for o in layout.obstacles:
        ax.add_patch(Rectangle((o[0], o[1]), o[2] - o[0], o[3] - o[1], facecolor="#8a8a8a", edgecolor="#444"))
    for w in layout.walls:
        ax.plot([w[0], w[2]], [w[1], w[3]], color="black", lw=3, solid_capstyle="projecting")
    for d in layout.doors.values():
        s = d.segment
        ax.plot([s[0], s[2]], [s[1], s[3]], color="#b07a2a", lw=1, ls=":")
    c = layout.charger
    ax.add_patch(Rectangle((c[0], c[1]), c[2] - c[0], c[3] - c[1], facecolor="#2d6cdf", edgecolor="#123"))
    ax.add_patch(Circle(layout.light, 4.5, facecolor="#ffd21f", edgecolor="#a80", zorder=5))
    if labels:
        ax.text(c[0] + 1, c[3] + 3, "charger", fontsize=7, color="#123", va="bottom")
    if locations:
        for name, loc in layout.locations.items():
            ax.plot(loc[0], loc[1], marker="x", color="#c0392b", ms=6)
            ax.text(loc[0] + 5, loc[1] - 12, name, fontsize=8, color="#c0392b")
    w, h = layout.size
    ax.set_xlim(-6, w + 6)
    ax.set_ylim(-6, h + 6)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def draw_robot(ax, pose, *, colour="#c0392b", reading: Reading | None = None, rays: bool = False) -> None:
    """Draw the robot disc and heading line, optionally its sonar rays (from a Reading) and light bits."""
    from matplotlib.patches import Circle

    x, y, hd = pose
    h = math.radians(hd)
    if rays and reading is not None:
        for k in range(N_RAYS):
            a = h + math.radians(RAY_STEP_DEG * k)
            r = reading.sonar_radius + float(reading.sonar[k])
            ca, sa = math.cos(a), math.sin(a)
            x0, y0 = x + ROBOT_RADIUS * ca, y + ROBOT_RADIUS * sa
            lit = reading.light[k]
            ax.plot([x0, x + r * ca], [y0, y + r * sa], color="#e0a800" if lit else "#5dade2",
                    lw=1.6 if lit else 0.7, zorder=3)
            if reading.door_edge[k]:
                ax.plot(x + r * ca, y + r * sa, "o", color="#8e44ad", ms=3, zorder=4)
    ax.add_patch(Circle((x, y), ROBOT_RADIUS, facecolor="white", edgecolor=colour, lw=1.5, zorder=6))
    ax.plot([x, x + ROBOT_RADIUS * math.cos(h)], [y, y + ROBOT_RADIUS * math.sin(h)], color=colour, lw=2,
            zorder=7)


def _figure(layout: Layout, dpi: int, scale: float, title: str | None):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    w, h = layout.size
    top = 0.35 if title else 0.0  # inches kept free for the title
    fig = Figure(figsize=(scale * w / 100 + 0.2, scale * h / 100 + 0.2 + top), dpi=dpi)
    FigureCanvasAgg(fig)
    frac = top / fig.get_figheight()
    ax = fig.add_axes((0.01, 0.01, 0.98, 0.98 - frac))
    if title:
        ax.set_title(title, fontsize=9)
    return fig, ax


def _to_rgb(fig) -> np.ndarray:
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()


def render_frame(layout: Layout, pose, *, reading: Reading | None = None, rays: bool = False,
                 trace: Sequence[Sequence[float]] | None = None, title: str | None = None,
                 locations: bool = False, dpi: int = 100, scale: float = 1.5) -> np.ndarray:
    """Top-down RGB image (H, W, 3) uint8 of the layout with the robot, its path so far and, with
    ``rays`` and a ``reading``, the sonar rays (blue; yellow where a light bit is on) and door-edge
    dots (purple)."""
    fig, ax = _figure(layout, dpi, scale, title)
    draw_layout(ax, layout, locations=locations)
    if trace is not None and len(trace) > 1:
        p = np.asarray(trace, dtype=float)
        ax.plot(p[:, 0], p[:, 1], color="#c0392b", lw=1, alpha=0.6)
    draw_robot(ax, pose, reading=reading, rays=rays)
    return _to_rgb(fig)


def render_figure_5_3(layout: Layout | str = "default", *, seed: int = 0, file=None, dpi: int = 100) -> np.ndarray:
    """Fig. 5.3's four panels: (a) the layout with L1..L4, (b) sonar at L3 facing north, (c) at L4 (they
    look alike: the hidden state of Ch. 8), (d) the light bits at L2 facing north. Readings are noisy, drawn
    with ``seed``; purple dots mark door-edge bits. Returns the RGB image; with ``file`` also writes a PNG."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    layout = layout if isinstance(layout, Layout) else Layout.load(layout)
    sim = RobotSim(layout, np.random.default_rng(seed))
    w, h = layout.size
    fig = Figure(figsize=(2 * (1.5 * w / 100 + 0.2), 2 * (1.5 * h / 100 + 0.5)), dpi=dpi)
    FigureCanvasAgg(fig)
    panels = [("(a) the robot's world, locations L1-L4", None, False),
              ("(b) sonar at L3 facing north (dots: door edges)", "L3", True),
              ("(c) sonar at L4 facing north", "L4", True),
              ("(d) light bits at L2 facing north (yellow rays)", "L2", True)]
    for i, (title, loc, rays) in enumerate(panels):
        ax = fig.add_subplot(2, 2, i + 1)
        draw_layout(ax, layout, locations=loc is None)
        ax.set_title(title, fontsize=9)
        if loc is not None:
            if loc not in layout.locations:
                raise ValueError(f"layout {layout.name!r} has no location {loc!r}; it has {sorted(layout.locations)}")
            sim.place(*layout.locations[loc])
            draw_robot(ax, sim.pose, reading=sim.sense(), rays=rays)
    fig.tight_layout()
    img = _to_rgb(fig)
    if file is not None:
        save_png(img, file)
    return img


def render_paths(layout: Layout, paths: Sequence[Sequence[Sequence[float]]], *,
                 labels: Sequence[str] | None = None, title: str | None = None, file=None,
                 robots: bool = True, dpi: int = 100, scale: float = 1.5,
                 locations: bool = False) -> np.ndarray:
    """Draw several trajectories (each a sequence of (x, y[, heading]) poses) on the layout.

    The start of each path is marked "S" (as in Fig. 5.7) and, with ``robots``, the robot disc is drawn
    at the first and last pose. Returns the RGB image; with ``file`` also writes it as PNG (atomically).
    """
    fig, ax = _figure(layout, dpi, scale, title)
    draw_layout(ax, layout, locations=locations)
    colours = ("#c0392b", "#2471a3", "#229954", "#7d3c98", "#d35400", "#17a589")
    for i, path in enumerate(paths):
        p = np.asarray(path, dtype=float)
        if p.ndim != 2 or p.shape[0] == 0 or p.shape[1] < 2:
            raise ValueError(f"path {i} must be a non-empty sequence of (x, y[, heading]) poses")
        col = colours[i % len(colours)]
        ax.plot(p[:, 0], p[:, 1], color=col, lw=1.5, marker=".", ms=3,
                label=None if labels is None else labels[i], zorder=8)
        ax.text(p[0, 0] - 16, p[0, 1] + 6, "S", fontsize=10, weight="bold", color=col, zorder=9)
        if robots and p.shape[1] >= 3:
            draw_robot(ax, p[0, :3], colour=col)
            draw_robot(ax, p[-1, :3], colour=col)
    if labels is not None:
        ax.legend(loc="upper left", fontsize=7, framealpha=0.9)
    img = _to_rgb(fig)
    if file is not None:
        save_png(img, file)
    return img


def save_png(image: np.ndarray, file) -> None:
    """Write an RGB uint8 image as PNG atomically."""
    import io

    from matplotlib.image import imsave

    buf = io.BytesIO()
    imsave(buf, np.asarray(image), format="png")
    atomic_write_bytes(file, buf.getvalue())


class HumanViewer:
    """A matplotlib window for render_mode="human"; silently inert (one warning) when headless."""

    def __init__(self):
        import matplotlib

        self._ok = matplotlib.get_backend().lower() not in ("agg", "pdf", "ps", "svg", "cairo", "template")
        self._fig = self._im = None
        if not self._ok:
            warnings.warn("render_mode='human' needs an interactive matplotlib backend; running headless, "
                          "frames are not shown (use render_mode='rgb_array')", stacklevel=3)

    def show(self, img: np.ndarray, fps: float) -> None:
        if not self._ok:
            return
        import matplotlib.pyplot as plt

        if self._fig is None:
            plt.ion()
            self._fig, ax = plt.subplots()
            ax.axis("off")
            self._im = ax.imshow(img)
        else:
            self._im.set_data(img)
        self._fig.canvas.draw_idle()
        plt.pause(1.0 / fps)

    def close(self) -> None:
        if self._fig is not None:
            import matplotlib.pyplot as plt

            plt.close(self._fig)
            self._fig = None

