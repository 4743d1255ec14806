"""Writers that respect their target, and all-or-nothing publication of a command's outputs.

- A regular file (or a new path) is written to a temporary file beside it, then renamed
  over it: it appears whole or not at all.
- A device, a FIFO or a socket (``/dev/null``, ``/dev/stdout``, a named pipe) is written
  in place: it is never replaced by a regular file.
- A symbolic link is followed: its target is written, the link stays.
- A directory, an empty path, a path ending in ``/`` or a path whose folder is missing
  is refused before any work (:func:`check_output`).

Inside ``with OutputSet():`` every write is staged and published only when the
whole block succeeds; on failure the staged files and the folders made for them
are removed, so nothing new remains. Outside one, each write publishes at once.
"""

from __future__ import annotations

import contextlib
import math
import os
import stat
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from types import TracebackType
from typing import Any

from rigidid.errors import InputError

__all__ = [
    "OutputSet",
    "atomic_path",
    "check_folder",
    "check_output",
    "first_non_finite",
    "write_bytes_atomic",
    "write_text_atomic",
]

_ACTIVE: ContextVar[OutputSet | None] = ContextVar("rigidid_output_set", default=None)


def _is_stream(path: Path) -> bool:
    """True when `path` (after symlinks) is an existing device, FIFO or socket."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return not stat.S_ISREG(mode) and not stat.S_ISDIR(mode)


def check_output(path: str | os.PathLike[str], *, option: str | None = None) -> Path:
    """Check that `path` can take an output file; return the path to write (symlinks followed).

    Raises
    ------
    InputError
        Naming the path (or `option` for an empty one): empty, a directory, a path
        ending in ``/``, a folder that does not exist or is not a folder, or not writable.
    """
    text = os.fspath(path)
    if not text.strip():
        raise InputError("empty output path", source=option or "output")
    if text.endswith(("/", os.sep)):
        raise InputError("is a folder path; give a file name", source=text)
    p = Path(text)
    if p.is_dir():
        raise InputError("is a directory, not a file", source=text)
    real = Path(os.path.realpath(p))
    if real.is_dir():
        raise InputError("is a directory, not a file", source=text)
    if _is_stream(real):
        if not os.access(real, os.W_OK):
            raise InputError("cannot write: permission denied", source=text)
        return real
    folder = real.parent
    if not folder.exists():
        raise InputError(f"cannot write: folder {str(p.parent)!r} does not exist", source=text)
    if not folder.is_dir():
        raise InputError(f"cannot write: {str(p.parent)!r} is not a folder", source=text)
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(f"cannot write: folder {str(p.parent)!r} is not writable", source=text)
    return real


def check_folder(path: str | os.PathLike[str], *, option: str | None = None) -> Path:
    """Check that `path` can be (or is) an output folder, without making it.

    Raises
    ------
    InputError
        Empty path, an existing non-folder, or a missing parent that is a file.
    """
    text = os.fspath(path)
    if not text.strip():
        raise InputError("empty output folder", source=option or "output")
    p = Path(text)
    if p.exists() and not p.is_dir():
        raise InputError("is not a folder", source=text)
    for parent in p.absolute().parents:
        if parent.exists():
            if not parent.is_dir():
                raise InputError(f"cannot make the folder: {str(parent)!r} is not a folder", source=text)
            if not os.access(parent, os.W_OK | os.X_OK) and not p.exists():
                raise InputError(f"cannot make the folder: {str(parent)!r} is not writable", source=text)
            break
    return p


class OutputSet:
    """Stage every output of a command; publish all of them only if the block succeeds.

    Use as ``with OutputSet() as outs:``. Writers of :mod:`rigidid.io` (through
    :func:`atomic_path`) join the innermost active set. ``outs.stdout(text)``
    stages text for standard output, written first at publication.
    """

    def __init__(self) -> None:
        self._files: list[tuple[Path, Path, str]] = []  # (temporary, target, shown name)
        self._streams: list[tuple[Path, Path, str]] = []
        self._stdout: list[str] = []
        self._folders: list[Path] = []
        self._scratch: Path | None = None
        self._outer: OutputSet | None = None
        self._token: Any = None
        self._depth = 0

    # -- staging
    def folder(self, path: str | os.PathLike[str], *, option: str | None = None) -> Path:
        """Make folder `path` (and missing parents) now; removed again if the block fails."""
        p = check_folder(path, option=option)
        missing = [q for q in [p, *p.parents] if not q.exists()]
        for q in reversed(missing):
            try:
                q.mkdir()
            except OSError as exc:
                raise InputError(f"cannot make the folder: {exc.strerror}", source=os.fspath(path)) from None
            self._folders.append(q)
        return p

    def stdout(self, text: str) -> None:
        """Stage `text` for standard output."""
        self._stdout.append(text)

    @contextmanager
    def path(self, path: str | os.PathLike[str]) -> Iterator[Path]:
        """Yield a temporary path to write; it is published to `path` when the set commits."""
        shown = os.fspath(path)
        target = check_output(path)
        stream = _is_stream(target)
        try:
            if stream:
                if self._scratch is None:
                    self._scratch = Path(tempfile.mkdtemp(prefix="rigidid-"))
                fd, name = tempfile.mkstemp(dir=self._scratch)
            else:
                fd, name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
        except OSError as exc:
            raise InputError(f"cannot write: {exc.strerror}", source=shown) from None
        os.close(fd)
        tmp = Path(name)
        try:
            if not stream:
                mask = os.umask(0o022)
                os.umask(mask)
                tmp.chmod(0o666 & ~mask)
            yield tmp
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
        (self._streams if stream else self._files).append((tmp, target, shown))

    # -- publication
    def commit(self) -> None:
        """Publish: standard output and in-place targets first, then rename every staged file."""
        try:
            for text in self._stdout:
                sys.stdout.write(text)
            if self._stdout:
                sys.stdout.flush()
            for tmp, target, shown in self._streams:
                try:
                    fd = os.open(target, os.O_WRONLY)
                    with os.fdopen(fd, "wb") as out, tmp.open("rb") as src:
                        while chunk := src.read(1 << 20):
                            out.write(chunk)
                except OSError as exc:
                    raise InputError(f"cannot write: {exc.strerror}", source=shown) from None
            for tmp, target, shown in self._files:
                try:
                    os.replace(tmp, target)
                except OSError as exc:
                    raise InputError(f"cannot write: {exc.strerror}", source=shown) from None
        except BaseException:
            self.rollback()
            raise
        self._files, self._streams, self._stdout, self._folders = [], [], [], []
        self._drop_scratch()

    def rollback(self) -> None:
        """Remove every staged file and every folder this set made."""
        for tmp, _, _ in [*self._files, *self._streams]:
            tmp.unlink(missing_ok=True)
        for folder in reversed(self._folders):
            with contextlib.suppress(OSError):
                folder.rmdir()
        self._files, self._streams, self._stdout, self._folders = [], [], [], []
        self._drop_scratch()

    def _drop_scratch(self) -> None:
        if self._scratch is not None:
            import shutil

            shutil.rmtree(self._scratch, ignore_errors=True)
            self._scratch = None

    def __enter__(self) -> OutputSet:
        self._token = _ACTIVE.set(self)
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        _ACTIVE.reset(self._token)
        if kind is None:
            self.commit()
        else:
            self.rollback()


@contextmanager
def transaction() -> Iterator[OutputSet]:
    """Join the active :class:`OutputSet`, or open one for this block."""
    active = _ACTIVE.get()
    if active is not None:
        yield active
        return
    with OutputSet() as outs:
        yield outs


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path for `path`; it is published when the block (or the active set) succeeds.

    A regular file or a new path is replaced by rename; a device or FIFO is written in
    place; a symlink's target is written. The file gets the usual permissions (0666
    less the umask), not ``mkstemp``'s 0600.

    Raises
    ------
    InputError
        If the path cannot take a file (see :func:`check_output`).
    """
    with transaction() as outs, outs.path(path) as tmp:
        yield tmp


def write_text_atomic(path: str | os.PathLike[str], text: str) -> None:
    """Write `text` (UTF-8) to `path` atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8", newline="")


def write_bytes_atomic(path: str | os.PathLike[str], data: bytes) -> None:
    """Write `data` to `path` atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def first_non_finite(data: Any, where: str = "") -> str | None:
    """Dotted location of the first NaN or infinity in nested dicts/lists of a JSON document, or None."""
    if isinstance(data, float):
        return None if math.isfinite(data) else (where or "(top)")
    if isinstance(data, dict):
        for key, value in data.items():
            found = first_non_finite(value, f"{where}.{key}" if where else str(key))
            if found:
                return found
    elif isinstance(data, (list, tuple)):
        for i, value in enumerate(data):
            found = first_non_finite(value, f"{where}.{i}" if where else str(i))
            if found:
                return found
    return None
