"""The one place that writes files: atomically, a single file (:func:`write_atomic`: a
temp file in the same folder, then rename) or a command's whole set of outputs
(:class:`OutputFolder`: a temp folder beside the target, moved into place only when
everything was written); and the one way mission files are read as text.

A write that fails is an :class:`~ftlbo_mav.errors.OutputError` naming the path, with
nothing of the outputs written and what was there untouched.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path

from ..errors import OutputError


def _file_mode() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


_FILE_MODE = _file_mode()


def _cannot(path: Path, exc: OSError) -> OutputError:
    return OutputError(f"{path}: cannot write: {exc.strerror or exc}; nothing was written")


def _make_parents(folder: Path) -> list[Path]:
    """Create ``folder`` and its missing parents; returns those created, deepest last."""
    missing = []
    p = folder
    while not p.exists():
        missing.append(p)
        if p.parent == p:
            break
        p = p.parent
    if p.exists() and not p.is_dir():
        raise OutputError(f"{p}: is a file, not a folder; nothing was written")
    for d in reversed(missing):
        d.mkdir()
    return list(reversed(missing))


def _remove_created(created: list[Path]) -> None:
    for d in reversed(created):
        try:
            d.rmdir()
        except OSError:
            pass


def write_atomic(path: str | Path, data: str | bytes) -> Path:
    """Write ``data`` to ``path`` so that readers see the old file or the new one, never half."""
    path = Path(path)
    created: list[Path] = []
    tmp = None
    try:
        if path.is_dir():
            raise OutputError(f"{path}: is a folder, not a file; nothing was written")
        created = _make_parents(path.parent)
        mode = "wb" if isinstance(data, bytes) else "w"
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name[:100]}.", suffix=".tmp", dir=path.parent)
        os.fchmod(fd, _FILE_MODE)  # mkstemp makes 0600; outputs are for others to read too
        text_args = {} if mode == "wb" else {"encoding": "utf-8", "newline": ""}
        with os.fdopen(fd, mode, **text_args) as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
        _remove_created(created)
        raise _cannot(path, exc) from None
    except BaseException:
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
        _remove_created(created)
        raise
    return path


class OutputFolder:
    """A command's outputs, written all or nothing into ``target``.

    ``with OutputFolder(target, replaces=PATTERNS) as out:`` makes a temporary folder
    beside ``target`` at once, so that an output that cannot be written fails before any
    work is done; :meth:`write` puts files there. Leaving the block normally moves them
    into ``target``: a ``target`` that did not exist is the temporary folder renamed;
    else, after checking that no name is a folder there, the files of ``target`` whose
    names match ``replaces`` (regular expressions: the outputs of an earlier run, say
    ``uav\\d+\\.waypoints``) and that this run did not write are removed, then each file
    is renamed in, ``last`` (a name) after the others. Leaving it by an exception (a
    failure, Ctrl-C) removes the temporary folder and leaves ``target`` untouched. Every
    ``OSError`` becomes an :class:`OutputError` naming the path.
    """

    def __init__(self, target: str | Path, *, replaces: Iterable[str] = (),
                 last: str | None = None, inputs: Iterable[str | Path] = ()):
        self.target = Path(target)
        self.replaces = [re.compile(p) for p in replaces]
        # the files this command reads: never overwritten, never removed as an old output
        self.inputs = [Path(p) for p in inputs if Path(p).is_file()]
        self.last = last
        self.names: list[str] = []
        self._tmp: Path | None = None
        self._created: list[Path] = []

    def __enter__(self) -> OutputFolder:
        t = self.target
        try:
            if t.exists() and not t.is_dir():
                raise OutputError(f"{t}: is a file, not a folder; nothing was written")
            for path in self.inputs:
                if (t.is_dir() and os.path.samefile(path.parent, t)
                        and any(p.fullmatch(path.name) for p in self.replaces)):
                    raise OutputError(f"{path}: an input of this command, in the output "
                                      f"folder {t} under a name the command writes; give "
                                      "another output folder (or rename the input); "
                                      "nothing was written")
            self._created = _make_parents(t.parent)
            self._tmp = Path(tempfile.mkdtemp(prefix=f".{t.name[:100]}.", suffix=".tmp",
                                              dir=t.parent))
            # the name itself must be possible (not too long, not under /proc...)
            probe = self._tmp / t.name
            probe.mkdir()
            probe.rmdir()
        except OSError as exc:
            self._discard()
            raise _cannot(t, exc) from None
        return self

    def write(self, name: str, data: str | bytes) -> Path:
        """Write ``data`` as ``name`` (a plain file name); returns its final path."""
        if Path(name).name != name:
            raise ValueError(f"{name!r}: a file name, not a path")
        path = self._tmp / name
        final = self.target / name
        for source in self.inputs:
            if final.exists() and os.path.samefile(final, source):
                raise OutputError(f"{final}: is an input of this command; give another "
                                  "output folder; nothing was written")
        try:
            if isinstance(data, bytes):
                path.write_bytes(data)
            else:
                path.write_text(data, encoding="utf-8", newline="")
            os.chmod(path, _FILE_MODE)
        except OSError as exc:
            raise _cannot(self.target / name, exc) from None
        if name not in self.names:
            self.names.append(name)
        return self.target / name

    def write_all(self, files: Mapping[str, str | bytes]) -> list[Path]:
        return [self.write(name, data) for name, data in files.items()]

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            self._discard()
            return
        try:
            self._commit()
        except OSError as exc:
            self._discard()
            raise _cannot(self.target, exc) from None
        except BaseException:
            self._discard()
            raise

    def _commit(self) -> None:
        t, tmp = self.target, self._tmp
        if not t.exists():
            os.rename(tmp, t)
            self._tmp = None
            return
        for name in self.names:
            if (t / name).is_dir():
                raise OutputError(f"{t / name}: is a folder; nothing was written")
        for old in t.iterdir():
            if (old.name not in self.names and old.is_file()
                    and any(p.fullmatch(old.name) for p in self.replaces)):
                old.unlink()
        order = [n for n in self.names if n != self.last] + [
            n for n in self.names if n == self.last]
        for name in order:
            os.replace(tmp / name, t / name)
        tmp.rmdir()
        self._tmp = None

    def _discard(self) -> None:
        if self._tmp is not None:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None
        _remove_created(self._created)
        self._created = []


def check_writable(target: str | Path) -> None:
    """:class:`OutputError` now when an :class:`OutputFolder` could not be written to
    ``target`` later (before a flight whose record would otherwise be lost); nothing is
    left behind."""
    out = OutputFolder(target)
    out.__enter__()
    out._discard()


def digest(text: str | bytes) -> str:
    """The SHA-256 of a file's content (text as UTF-8): how plan.json names the mission
    files it was written with."""
    data = text.encode("utf-8") if isinstance(text, str) else text
    return hashlib.sha256(data).hexdigest()


def read_mission_text(path: str | Path) -> str:
    """A mission file's text; :class:`MissionFileError` naming the file when unreadable."""
    from ..errors import MissionFileError
    from ..inputs import read_user_text

    path = Path(path)
    return read_user_text(path, error=lambda problem: MissionFileError(f"{path}: {problem}"))
