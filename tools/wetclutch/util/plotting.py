"""Matplotlib for the reports (HIL replay and identification): backend, figures, axes style, saving.

matplotlib is imported on first use only (the commands that plot nothing do not load it), on the
Agg backend: the reports are files, no display is needed.
"""
from __future__ import annotations

from pathlib import Path

from .atomic import atomic_path

DPI = 110


def pyplot():
    """matplotlib.pyplot on the Agg backend."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def subplots(*args, **kwargs):
    """A figure and its axes: pyplot.subplots on the Agg backend."""
    return pyplot().subplots(*args, **kwargs)


def figure(**kwargs):
    """An empty figure (for 3D axes: figure.add_subplot(projection="3d"))."""
    return pyplot().figure(**kwargs)


def style(ax, xlabel: str | None = None, ylabel: str | None = None, title: str | None = None,
          legend: bool | dict = False, grid: str | None = "major"):
    """Labels, title, legend (True, or the legend's keyword arguments) and the light grid every plot has
    (grid: "major", "both", or None for none). Returns ax."""
    if xlabel is not None:
        ax.set_xlabel(xlabel)
    if ylabel is not None:
        ax.set_ylabel(ylabel)
    if title is not None:
        ax.set_title(title)
    if legend:
        ax.legend(**(legend if isinstance(legend, dict) else {}))
    if grid:
        ax.grid(alpha=0.3, which=grid)
    return ax


def fit_y_to_x(ax, margin: float = 0.05):
    """The y limits fitted to what is drawn inside the x limits: lines and scatter points in data
    coordinates (shading and axvline, drawn in axes coordinates, do not count), plus `margin` of the span on
    each side (a factor on a log axis). matplotlib's autoscale fits all the data, also what set_xlim hides:
    a record longer than its window scales its panel to values nobody sees. Returns ax."""
    import numpy as np
    x_lo, x_hi = sorted(ax.get_xlim())
    shown = []
    for artist in [*ax.get_lines(), *ax.collections]:
        if hasattr(artist, "get_xydata"):                 # a line
            transform, xy = artist.get_transform(), artist.get_xydata()
        elif hasattr(artist, "get_offset_transform"):     # scatter points: their offsets are the data
            transform, xy = artist.get_offset_transform(), artist.get_offsets()
        else:
            continue
        if transform != ax.transData:
            continue
        xy = np.asarray(xy, dtype=float)
        if xy.ndim != 2 or xy.shape[0] == 0:
            continue
        inside = (xy[:, 0] >= x_lo) & (xy[:, 0] <= x_hi) & np.isfinite(xy[:, 1])
        shown.append(xy[inside, 1])
    y = np.concatenate(shown) if shown else np.empty(0)
    log = ax.get_yscale() == "log"
    if log:
        y = y[y > 0]
    if y.size == 0:
        return ax
    lo, hi = float(np.min(y)), float(np.max(y))
    if log:
        ratio = (hi / lo) ** margin if hi > lo else 2.0
        ax.set_ylim(lo / ratio, hi * ratio)
    else:
        pad = margin * (hi - lo) if hi > lo else max(abs(hi) * margin, 1.0)
        ax.set_ylim(lo - pad, hi + pad)
    return ax


def save(fig, path: Path | str) -> str:
    """Lay the figure out, write it (atomic.atomic_path: a temporary renamed into place, so a reader never
    sees half a PNG and a failure leaves nothing) and close it. Returns the path as a string."""
    path = Path(path)
    try:
        fig.tight_layout()
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=DPI, format=path.suffix.lstrip(".") or "png")
    finally:
        pyplot().close(fig)
    return str(path)
