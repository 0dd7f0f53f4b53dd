"""Reading a file a user names: only a regular file, of a bounded size, as UTF-8 text.

Every command reads its inputs (scenario, GeoJSON layer, mission files, plan.json, a
signing key) through :func:`read_user_text`, so that a FIFO is refused instead of waited
on, a device that never ends (``/dev/zero``) is refused instead of read until memory runs
out, a UTF-8 byte-order mark (as Windows editors write) is dropped, and every problem is
one message naming the file.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Callable
from pathlib import Path

MAX_INPUT_BYTES = 64 * 1024 * 1024  # far above any scenario, layer or plan we write
_BOM = b"\xef\xbb\xbf"


def read_user_text(path: str | Path, *, error: Callable[[str], Exception],
                   limit_bytes: int = MAX_INPUT_BYTES) -> str:
    """The text of ``path``; ``error(problem)`` builds the exception raised when it is
    missing, not a regular file, larger than ``limit_bytes``, unreadable or not UTF-8."""
    path = Path(path)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise error("no such file") from None
    except OSError as exc:
        raise error(f"cannot read: {exc.strerror or exc}") from None
    if stat.S_ISDIR(info.st_mode):
        raise error("is a folder, not a file")
    if not stat.S_ISREG(info.st_mode):
        raise error("is not a regular file (a FIFO, a device or a socket): give a file")
    if info.st_size > limit_bytes:
        raise error(f"is {info.st_size / 2**20:.0f} MiB: at most "
                    f"{limit_bytes / 2**20:.0f} MiB")
    try:
        with open(path, "rb") as f:
            data = f.read(limit_bytes + 1)
    except OSError as exc:
        raise error(f"cannot read: {exc.strerror or exc}") from None
    if len(data) > limit_bytes:
        raise error(f"is larger than {limit_bytes / 2**20:.0f} MiB")
    if data.startswith(_BOM):
        data = data[len(_BOM):]
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"is not UTF-8 text (byte {exc.start} is {data[exc.start]:#04x}); "
                    "save it as UTF-8") from None
