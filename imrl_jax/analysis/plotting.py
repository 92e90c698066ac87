"""The figures' one style: the colours (floor lines, experts, what the retina sees, the conditions' lines), the
figure, an axis' title, labels and grid, and saving at one resolution.

Every picture of the arena (:mod:`imrl_jax.analysis.arena_figures`, the paper's Fig. 1) and every chart
(:mod:`imrl_jax.analysis.charts`, Fig. 3) is drawn in it, as are the studies' figures. A figure is made
without pyplot (nothing global is touched, a notebook shows it once); :func:`save` writes it. matplotlib is
imported lazily, inside the functions, so importing the package stays light.
"""

from __future__ import annotations

import os

from imrl_jax.conditions import CONDITIONS as TABLE

FLOOR_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")  # red, green, blue lines
EXPERT_COLOURS = ("#ff7f0e", "#9467bd", "#111111", "#8c564b", "#e377c2", "#7f7f7f")
DPI = 110  # resolution of saved figures
NOTHING_COLOUR = "#d9d9d9"  # a receptor that sees no colour
SEEN_COLOURS = FLOOR_COLOURS + (NOTHING_COLOUR,)  # red, green, blue, nothing
CONDITION_STYLES = {name: condition.style for name, condition in TABLE.items()}


def new_figure(width: float, height: float):
    """An empty Figure of the given size in inches (no pyplot: safe in scripts and notebooks)."""
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height))


def save(fig, path: str, dpi: int = DPI) -> str:
    """Write a figure (format from the extension; its folder made) through a temporary file renamed when done; the path."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    if not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    folder, name = os.path.split(os.path.abspath(path))
    base, ext = os.path.splitext(name)
    os.makedirs(folder, exist_ok=True)
    tmp = os.path.join(folder, f".{base}.tmp-{os.getpid()}{ext}")
    try:
        fig.savefig(tmp, dpi=dpi)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    return path


def animation_writer(path: str, fps: int, stills: tuple[str, ...] = ()):
    """The matplotlib writer of an animation into ``path``: ``.gif`` with Pillow, ``.mp4`` with ffmpeg (which must be
    on PATH); another extension is a ValueError naming the ones that work (``stills``: a caller's still formats)."""
    from matplotlib.animation import FFMpegWriter, PillowWriter

    writers = {".gif": PillowWriter, ".mp4": FFMpegWriter}
    ext = "." + path.rsplit(".", 1)[-1].lower()
    if ext not in writers:
        formats = [*stills, *writers]
        raise ValueError(f"unknown format {ext} (use {', '.join(formats[:-1])} or {formats[-1]})")
    return writers[ext](fps=fps)


def style_axis(ax, title: str = "", xlabel: str = "", ylabel: str = "", grid: bool = True) -> None:
    """Title, labels, tick sizes and grid of an axis in the figures' style."""
    if title:
        ax.set_title(wrap_title(ax, title), fontsize=9)
    if xlabel:
        ax.set_xlabel(xlabel, fontsize=8)
    if ylabel:
        ax.set_ylabel(ylabel, fontsize=8)
    ax.tick_params(which="both", labelsize=7)
    if grid:
        ax.grid(alpha=0.3)


def wrap_title(ax, title: str, fontsize: float = 9) -> str:
    """The title broken into lines that fit the axis' width (a 9-point character is about 5 points wide)."""
    import textwrap

    width_inches = ax.figure.get_figwidth() * ax.get_position().width
    chars = max(20, int(width_inches * 72 / (0.56 * fontsize)))
    return "\n".join(textwrap.fill(line, chars, break_long_words=False) for line in title.split("\n"))
