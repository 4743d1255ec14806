"""One line for a damaged binary file: the libraries' own exceptions turned into :class:`InputError`.

The binary readers hand a file to zipfile, zlib, numpy, scipy, h5py and npTDMS,
each of which signals a damaged file with its own exception type (``BadZipFile``
for a truncated ``.npz``, ``KeyError`` for an HDF5 link to nowhere, ``TypeError``
for a WAV format field scipy maps to no dtype, ``MemoryError`` for a header that
claims more values than memory holds). :func:`reading` and :func:`guarded` turn
those into one :class:`~rigidid.errors.InputError` naming the file, for the
whole read and for each block of a streamed one.
"""

from __future__ import annotations

import contextlib
import struct
import tokenize
import zipfile
import zlib
from collections.abc import Iterator
from typing import TypeVar

from rigidid.errors import InputError

__all__ = ["guarded", "reading"]

T = TypeVar("T")

# what a damaged file raises inside the libraries a binary reader calls (numpy parses a .npy header with
# Python's tokenizer: TokenError, SyntaxError)
_DAMAGE = (zipfile.BadZipFile, zlib.error, struct.error, EOFError, OSError, KeyError, ValueError, TypeError,
           IndexError, ZeroDivisionError, OverflowError, RuntimeError, SyntaxError,
           tokenize.TokenError)  # fmt: skip


def _reason(exc: BaseException) -> str:
    text = str(exc).strip()
    if isinstance(exc, KeyError) and len(text) > 1 and text[0] == text[-1] and text[0] in "'\"":
        text = text[1:-1]  # KeyError quotes its message
    first = text.splitlines()[0].strip() if text else ""
    return first[:160] or type(exc).__name__


@contextlib.contextmanager
def reading(src: str, what: str) -> Iterator[None]:
    """Run a read of file `src` (a `what` file: ``".npz"``...), any damage one :class:`InputError`.

    Raises
    ------
    InputError
        ``"not a readable .npz file (Bad CRC-32 for file 'data.npy')"``; for a
        header that claims more values than memory holds, says so.
    """
    try:
        yield
    except InputError:
        raise
    except MemoryError:
        raise InputError(
            f"its header claims more values than memory holds: a damaged {what} file", source=src
        ) from None
    except _DAMAGE as exc:
        raise InputError(f"not a readable {what} file ({_reason(exc)})", source=src) from None


def guarded(blocks: Iterator[T], src: str, what: str) -> Iterator[T]:
    """`blocks` with each step under :func:`reading` (a streamed file damaged further on); closes it at the end."""
    try:
        while True:
            with reading(src, what):
                try:
                    item = next(blocks)
                except StopIteration:
                    return
            yield item
    finally:
        close = getattr(blocks, "close", None)
        if close is not None:
            close()
