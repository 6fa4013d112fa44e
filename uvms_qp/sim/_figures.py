"""Matplotlib set-up shared by the run figures and the scheme-comparison figures (PNG, headless)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

#: Resolution of every written figure [dots per inch].
DPI = 110


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


def save(fig: Any, path: Path) -> Path:
    """Lay out ``fig``, write it to ``path`` (PNG at :data:`DPI`), close it; return ``path``."""
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    pyplot().close(fig)
    return path
