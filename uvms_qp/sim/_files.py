"""Atomic writes of the output files (``results.json``, figures, tables, the 3-D view).

A file is written into a temporary file of the same directory and renamed over the target
(``os.replace``): a reader never sees a partial file, a failed write leaves the previous one, and a
target that is a symbolic link is replaced by the new file instead of being followed (the file it
pointed to, possibly outside the output directory, is left untouched). The result has mode
:data:`FILE_MODE` (``rw-r--r--``), like a file written by ``open``.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO

#: Permissions of every written output file.
FILE_MODE = 0o644


def write_atomic(path: str | Path, content: bytes | str | Callable[[IO[bytes]], None]) -> Path:
    """Write ``content`` to ``path`` atomically, replacing (never following) a link there.

    Args:
        path: Target file; its directory must exist.
        content: Bytes, text (written as UTF-8) or a function that writes into a binary handle.

    Returns:
        ``path`` as a Path.

    Raises:
        OSError: the directory cannot be written, or ``path`` is a directory.
    """
    target = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as handle:
            if isinstance(content, str):
                handle.write(content.encode("utf-8"))
            elif isinstance(content, bytes):
                handle.write(content)
            else:
                content(handle)
        os.chmod(tmp, FILE_MODE)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return target
