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
