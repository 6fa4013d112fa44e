"""Matplotlib set-up shared by the run figures and the scheme-comparison figures (PNG, headless).

Every figure is written atomically (:func:`uvms_qp.sim._files.write_atomic`): a figure path that
is a symbolic link is replaced, never followed. :class:`FigureProgress` reports the figures as
they are written (a transient bar on a terminal, one line per figure otherwise).
"""

from __future__ import annotations

import io
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from ._files import write_atomic

#: Resolution of every written figure [dots per inch].
DPI = 110
#: Writing figures that has taken longer than this [s] starts reporting progress.
PROGRESS_AFTER = 2.0
#: A figure builder: draws and returns one matplotlib figure.
Builder = Callable[[], Any]


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the non-interactive Agg back-end (imported on first use)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def output_dir(out_dir: str | Path) -> Path:
    """``out_dir`` as a Path, created (with its parents) if needed."""
    directory = Path(out_dir)
    directory.mkdir(parents=True, exist_ok=True)
    return directory


def lay_out(fig: Any) -> Any:
    """Lay out ``fig`` as it will be written (tight, unless it has a layout engine); return it."""
    if not fig.get_layout_engine():
        fig.tight_layout()
    return fig


def save(fig: Any, path: Path) -> Path:
    """Lay out ``fig``, write it atomically to ``path`` (PNG at :data:`DPI`), close it."""
    lay_out(fig)
    buffer = io.BytesIO()
    try:
        fig.savefig(buffer, format="png", dpi=DPI)
    finally:
        pyplot().close(fig)
    return write_atomic(path, buffer.getvalue())


def time_axis(ax: Any) -> None:
    """Label ``ax``'s horizontal axis as the time [s] and show its tick labels."""
    ax.set_xlabel("t [s]")
    ax.tick_params(axis="x", labelbottom=True)


def unit_label(unit: str) -> str:
    """``unit`` for an axis label, a power as a superscript (``m^3`` in mathtext)."""
    base, power, exponent = unit.partition("^")
    return f"{base}$^{{{exponent}}}$" if power else unit


def min_span(ax: Any, values: Any, span: float) -> None:
    """Give ``ax`` a vertical range of at least ``span`` around ``values``.

    A series that barely moves (rounding noise of 1e-15 m on a vehicle held in place) is drawn as
    the flat line it is instead of being stretched over the whole panel.
    """
    data = np.asarray(values, dtype=np.float64)
    data = data[np.isfinite(data)]
    if not data.size:
        return
    low, high = float(data.min()), float(data.max())
    if high - low < span:
        centre = 0.5 * (low + high)
        ax.set_ylim(centre - 0.5 * span, centre + 0.5 * span)


#: Legend text of the command-rate window (rates figures).
RATE_WINDOW_LABEL = "command-rate window"
#: Legend text of the payload's pick-up on a dynamic plant.
PAYLOAD_LABEL = "payload attached"


def event_label(event: dict[str, Any]) -> str:
    """Legend text of an event line: ``event TIME s: TASK KEY = VALUE`` (a run's ``events``)."""
    changes = ", ".join(f"{key} = {_short(value)}" for key, value in event["update"].items())
    return f"event {event['time']:g} s: {event['task']} {changes}".rstrip()


def _short(value: Any) -> str:
    text = f"{value:g}" if isinstance(value, float | int) else str(value)
    return text if len(text) <= 24 else text[:23] + "\u2026"


def mark_events(ax: Any, events: Iterable[dict[str, Any]],
                payload_time: float | None = None) -> None:
    """Dotted vertical lines, labelled for the legend: each event, and the payload's pick-up."""
    for event in events:
        ax.axvline(event["time"], color="0.6", linestyle=":", linewidth=1.0,
                   label=event_label(event))
    if payload_time is not None:
        ax.axvline(payload_time, color="tab:brown", linestyle=":", linewidth=1.0,
                   label=PAYLOAD_LABEL)


def legend(ax: Any, sources: Iterable[Any] | None = None, **kwargs: Any) -> None:
    """A legend on ``ax``: the labelled artists of ``sources`` (default ``ax``), each label once.

    Nothing is drawn when no artist is labelled.
    """
    entries: dict[str, Any] = {}
    for source in sources if sources is not None else (ax,):
        for handle, label in zip(*source.get_legend_handles_labels(), strict=True):
            entries.setdefault(label, handle)
    if entries:
        ax.legend(list(entries.values()), list(entries), **kwargs)


class FigureProgress:
    """Report figures as they are written, once writing has taken :data:`PROGRESS_AFTER` [s].

    On a terminal a transient bar (standard error), otherwise one line per figure.

    Args:
        total: Number of figures to write.
        label: What is being written (shown before the count).
        enabled: False: report nothing.
    """

    def __init__(self, total: int, label: str, enabled: bool) -> None:
        self.total = total
        self.label = label
        self.enabled = enabled and total > 0
        self.done = 0
        self._bar: Any = None
        self._task: Any = None
        self._console: Any = None
        self._start = time.perf_counter()

    def _begin(self) -> None:
        from rich.console import Console

        self._console = Console(stderr=True)
        if self._console.is_terminal:
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

            self._bar = Progress(TextColumn(self.label), BarColumn(), MofNCompleteColumn(),
                                 TextColumn("{task.description}"), console=self._console,
                                 transient=True)
            self._bar.start()
            self._task = self._bar.add_task("", total=self.total, completed=self.done)

    def start(self, name: str) -> None:
        """Announce that figure ``name`` is being drawn."""
        if not self.enabled:
            return
        elapsed = time.perf_counter() - self._start
        if self._console is None:
            if elapsed < PROGRESS_AFTER:
                return
            self._begin()
        if self._bar is not None:
            self._bar.update(self._task, completed=self.done, description=name)
        else:
            self._console.print(f"{self.label}: {self.done + 1}/{self.total} {name} "
                                f"({elapsed:.1f} s)", markup=False, highlight=False)

    def finish(self) -> None:
        """Count the figure as written."""
        self.done += 1
        if self._bar is not None:
            self._bar.update(self._task, completed=self.done)

    def close(self) -> None:
        """Remove the bar."""
        if self._bar is not None:
            self._bar.stop()
            self._bar = None


def write_figures(builders: Iterable[tuple[str, Builder]], directory: Path, *,
                  label: str = "figures", progress: bool = False) -> list[Path]:
    """Build each figure and write it as ``directory/<name>``; return the written paths.

    Args:
        builders: ``(file name, builder)`` pairs.
        directory: Existing output directory.
        label: Label of the progress report.
        progress: Report the figures as they are written.
    """
    todo = list(builders)
    bar = FigureProgress(len(todo), label, progress)
    paths: list[Path] = []
    try:
        for name, build in todo:
            bar.start(name)
            paths.append(save(build(), directory / name))
            bar.finish()
    finally:
        bar.close()
    return paths


def built(builders: Iterable[tuple[str, Builder]]) -> Iterator[tuple[str, Any]]:
    """``(name, figure)`` of every builder (for inspection and tests)."""
    for name, build in builders:
        yield name, build()
