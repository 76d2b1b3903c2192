"""The mechanisms moving: an animated GIF of the recorded co-simulation, of any mechanism that
draws itself (its `Scene`, in its module).

Each frame shows one recorded communication point of the run's last shaft revolution (one
stitch): the frames are the samples nearest to FRAMES equally spaced crank angles. What the run
produced (the shaft angle, the punch's height and forces, the table's motion, the points the
FMUs output) is drawn as recorded; the joints that no FMU outputs come from the linkage model at
the recorded crank angle. Everything is drawn to scale in millimetres, except what a frame says
is exaggerated (the carriage's deflection).

Every mechanism marks one recorded point in pure red (TRACKED): the punch's tip, the feed dog M,
the take-up eye E, the table. `Animation` tells where its axes lie in the picture, so that a test
can find that point in a frame from the recorded columns alone.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sewfmu.scenarios.files.matplotlib_home import pyplot
from sewfmu.scenarios.mechanisms.base import RoleError, column, whole_revolution

FRAMES = 36
FRAME_MS = 90                 # display time of a frame
TRACKED = "#ff0000"           # the recorded point every animation marks
SIZE_IN = (5.0, 4.2)          # figure size (in) and resolution: 400 x 336 pixels
DPI = 80


@dataclass
class Animation:
    """Where an animation's pictures put its drawing: enough to find a drawn point in a frame."""
    path: Path
    samples: list[int]                      # the recorded sample of each frame
    size: tuple[int, int]                   # picture width, height (pixels)
    axes_box: tuple[float, float, float, float] = (0, 0, 0, 0)   # left, top, right, bottom (px)
    limits: tuple[float, float, float, float] = (0, 0, 0, 0)     # xmin, xmax, ymin, ymax
    tracked: list[tuple[float, float]] = field(default_factory=list)  # per frame, drawing units

    def pixel(self, x: float, y: float) -> tuple[float, float]:
        """The picture pixel (column, row from the top) of a point in drawing units."""
        left, top, right, bottom = self.axes_box
        xmin, xmax, ymin, ymax = self.limits
        return (left + (x - xmin) / (xmax - xmin) * (right - left),
                bottom - (y - ymin) / (ymax - ymin) * (bottom - top))


def frame_samples(phi: np.ndarray, frames: int = FRAMES) -> list[int]:
    """The recorded samples nearest to `frames` equally spaced angles of the last revolution."""
    start, _ = whole_revolution(float(phi[-1]))
    targets = start + 2 * math.pi * np.arange(frames) / frames
    idx = np.clip(np.searchsorted(phi, targets), 1, len(phi) - 1)
    nearer_left = (targets - phi[idx - 1]) < (phi[idx] - targets)
    # within the revolution: with non-uniform samples (the adaptive master) the nearest sample to
    # its first angle may lie before it
    inside = phi[idx - 1] >= start - 1e-12
    return [int(i) for i in np.where(nearer_left & inside, idx - 1, idx)]


def can_animate(scenario) -> bool:
    """Whether the scenario's mechanism draws itself."""
    return scenario.mechanism is not None and scenario.mechanism.animated


def _scene(result):
    """The drawing of the run's mechanism at its recorded samples."""
    found = result.scenario.mechanism
    if found is None or not found.animated:
        raise RoleError(f"no drawing of the {result.scenario.analysis!r} analysis's mechanism")
    return found.Scene(result)


def animate(result, path: Path) -> Animation:
    """Write the GIF of a run of an animated analysis; return where its drawing lies."""
    from PIL import Image  # pillow: only when animating

    plt = pyplot()          # matplotlib, its files out of the user's home
    scene = _scene(result)
    samples = frame_samples(column(result, "shaft", "phi"))
    fig, ax = plt.subplots(figsize=SIZE_IN, dpi=DPI)
    images, tracked = [], []
    try:
        for i in samples:
            ax.clear()
            tracked.append(scene.draw(ax, i))
            ax.plot(*tracked[-1], "o", color=TRACKED, ms=6, zorder=10)
            ax.set_xlim(scene.xlim)
            ax.set_ylim(scene.ylim)
            ax.set_aspect("equal" if scene.to_scale else "auto", adjustable="box")
            fig.canvas.draw()
            rgb = np.asarray(fig.canvas.buffer_rgba())[..., :3]
            images.append(Image.fromarray(np.ascontiguousarray(rgb)))
        width, height = fig.canvas.get_width_height()
        box = ax.get_window_extent()
        xmin, xmax = ax.get_xlim()
        ymin, ymax = ax.get_ylim()
    finally:
        plt.close(fig)
    # one palette for all frames, from a sheet of every fourth frame, so that colours that show
    # only in some frames (the force bar, the traced path) are in it and do not flicker
    sheet = Image.new("RGB", (width, height * len(images[::4])))
    for k, image in enumerate(images[::4]):
        sheet.paste(image, (0, k * height))
    palette = sheet.quantize(colors=64, method=Image.Quantize.MEDIANCUT)
    frames = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in images]
    path = Path(path)
    frames[0].save(path, save_all=True, append_images=frames[1:], duration=FRAME_MS, loop=0,
                   optimize=False)
    return Animation(path, samples, (width, height),
                     (box.x0, height - box.y1, box.x1, height - box.y0), (xmin, xmax, ymin, ymax),
                     tracked)


def reach(joints_at, samples, margin: float) -> tuple[tuple[float, float], tuple[float, float]]:
    """The drawing's limits: the box of every joint over (90 of) the samples, with a margin.
    `joints_at(i)` gives the joints (x, y) at sample i."""
    points = [xy for i in samples[:: max(1, len(samples) // 90)] for xy in joints_at(i).values()]
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    return (min(xs) - margin, max(xs) + margin), (min(ys) - margin, max(ys) + margin)


def angle_label(result, i: int) -> str:
    """Crank angle within the last revolution and the time of sample i."""
    phi = column(result, "shaft", "phi")
    within = math.degrees(phi[i] - whole_revolution(float(phi[-1]))[0]) % 360.0
    return f"φ = {within:5.1f}°   t = {result.time[i]:.4f} s"


def linkage(result, frames: int = FRAMES) -> dict:
    """The mechanism's drawing as numbers, for a page that draws it itself: at `frames` equally
    spaced crank angles of the last revolution, every point (mm) and the chains of bars between
    them; the recorded point every animation marks is `tracked`."""
    scene = _scene(result)
    phi = column(result, "shaft", "phi")
    samples = frame_samples(phi, frames)
    start, _ = whole_revolution(float(phi[-1]))
    at = [scene.points(i) for i in samples]
    return {"samples": samples,
            "crank_deg": [math.degrees(float(phi[i]) - start) % 360.0 for i in samples],
            "time": [float(result.time[i]) for i in samples],
            "points": {name: [tuple(map(float, p[name])) for p in at] for name in at[0]},
            "chains": [list(c) for c in scene.chains()], "tracked": scene.tracked,
            "xlim": tuple(map(float, scene.xlim)), "ylim": tuple(map(float, scene.ylim)),
            "to_scale": scene.to_scale}
