"""Atomic text-file replacement for the files a GCS session edits (.parm, WPL).

A crash or a full disk mid-write must never leave a half-written parameter or
mission file: write a temporary file in the same folder, fsync it, rename it
over the target (atomic on POSIX), and remove the temporary on any failure.
"""

from __future__ import annotations

import os
import tempfile


def write_text_atomic(path: str | os.PathLike, text: str, *, encoding: str, error_cls,
                      what: str) -> None:
    """Replace `path` with `text`; failures raise error_cls naming `what` and the fix."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    try:
        fd, tmp = tempfile.mkstemp(prefix=".silbridge-", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise error_cls(f"cannot write {what} {path!r}: {exc.strerror or exc}; check that the "
                        f"folder exists and is writable") from None
    try:
        with os.fdopen(fd, "w", encoding=encoding) as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
