"""Output files written atomically: the one writer of every command that writes files.

Each file is written to a temporary file in its own directory (``.NAME.XXXXXXXX.tmp``) and renamed
over the final path with os.replace only once everything has been written, so a reader never sees
half a file and a failure (a full disk, an unwritable directory, an exception half way) leaves no
partial or temporary file behind. Several files staged in one ``Staged`` block are renamed together
at its end: all or nothing for the block (the renames themselves need no space and do not fail on a
full disk). While a ``Staged`` block is active, every other write through this module in the same
thread or task (``write_text``, ``open_atomic``, ``atomic_path``, a nested ``Staged``; so also
plotting.save) joins it: a command makes its whole output all or nothing by wrapping its writing in
one block, without passing the block down to the helpers that write.

An OSError while staging or renaming is raised again with the *final* path as its filename and the
OS reason as its strerror (``str(e.filename) + ": " + e.strerror`` reads
"out/identify/figures.json: No space left on device"), never the temporary's name or None.

    with Staged() as out:
        out.write_text(out_dir / "a.h", text)
        with out.open(out_dir / "b.csv", newline="") as f:
            csv.writer(f).writerows(rows)
        with out.path(out_dir / "c.png") as tmp:   # for writers that take a path (savefig, ...)
            fig.savefig(tmp, format="png")

    write_text(path, text)                         # one file
"""
from __future__ import annotations

import contextlib
import contextvars
import errno
import os
import tempfile
from pathlib import Path
from typing import IO, Iterator


def _umask() -> int:
    """The process's umask (read by setting it; the command line is single-threaded)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def named_error(e: OSError, path: Path | str) -> OSError:
    """The OSError e, naming path (the final output, not a temporary) and the OS reason."""
    reason = e.strerror or (os.strerror(e.errno) if e.errno else str(e))
    return OSError(e.errno, reason, str(path))


def check_writable(final: Path | str) -> None:
    """Before a long computation, the error its write would meet, naming final: a regular file on its path,
    no permission to create a file where it goes (probed with a temporary, removed at once; nothing else is
    created). A full disk shows only when written."""
    final = Path(final)
    where = final.parent
    while not where.exists() and where != where.parent:   # the nearest existing directory on the path
        where = where.parent
    if not where.is_dir():
        raise named_error(OSError(errno.ENOTDIR, os.strerror(errno.ENOTDIR)), final)
    try:
        fd, probe = tempfile.mkstemp(dir=where, prefix=f".{final.name}.", suffix=".tmp")
    except OSError as e:
        raise named_error(e, final) from None
    os.close(fd)
    os.unlink(probe)


_ACTIVE: contextvars.ContextVar["Staged | None"] = contextvars.ContextVar("wetclutch_atomic_active", default=None)


class Staged:
    """Temporaries beside their final paths, renamed over them together when the block ends without an
    exception; on any exception (or commit failure) every temporary is removed and the finals untouched.
    Entered while another block is active, it joins that one (``with`` gives the outer block)."""

    def __init__(self) -> None:
        self._staged: list[tuple[Path, Path]] = []   # (temporary, final)
        self._token = None
        self._joined = False

    def __enter__(self) -> "Staged":
        outer = _ACTIVE.get()
        if outer is not None:
            self._joined = True
            return outer
        self._token = _ACTIVE.set(self)
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        if self._joined:
            self._joined = False
            return False          # the outer block commits or discards
        _ACTIVE.reset(self._token)
        self._token = None
        try:
            if exc_type is None:
                self.commit()
        finally:
            self.discard()
        return False

    @contextlib.contextmanager
    def path(self, final: Path | str) -> Iterator[Path]:
        """A temporary path for final, for a writer that opens the file itself. An OSError inside the block
        is raised again naming final."""
        final = Path(final)
        try:
            fd, tmp = tempfile.mkstemp(dir=final.parent, prefix=f".{final.name}.", suffix=".tmp")
        except OSError as e:
            raise named_error(e, final) from None
        tmp = Path(tmp)
        self._staged.append((tmp, final))
        try:
            os.fchmod(fd, 0o666 & ~_umask())   # as open() would create it, not mkstemp's 0600
        finally:
            os.close(fd)
        try:
            yield tmp
        except OSError as e:
            raise named_error(e, final) from None

    @contextlib.contextmanager
    def open(self, final: Path | str, mode: str = "w", encoding: str | None = "utf-8",
             newline: str | None = "\n") -> Iterator[IO]:
        """The temporary of final opened for writing (text: UTF-8, '\\n' line ends unless told)."""
        if "b" in mode:
            encoding = newline = None
        with self.path(final) as tmp:
            with open(tmp, mode, encoding=encoding, newline=newline) as f:
                yield f

    def write_text(self, final: Path | str, text: str, encoding: str = "utf-8", newline: str | None = "\n") -> None:
        with self.open(final, "w", encoding=encoding, newline=newline) as f:
            f.write(text)

    def write_bytes(self, final: Path | str, data: bytes) -> None:
        with self.open(final, "wb") as f:
            f.write(data)

    def commit(self) -> None:
        """Rename every temporary over its final path, in the order staged."""
        while self._staged:
            tmp, final = self._staged[0]
            try:
                os.replace(tmp, final)
            except OSError as e:
                raise named_error(e, final) from None
            self._staged.pop(0)

    def discard(self) -> None:
        """Remove the temporaries not yet renamed."""
        for tmp, _ in self._staged:
            with contextlib.suppress(OSError):
                tmp.unlink()
        self._staged.clear()


def write_text(path: Path | str, text: str, encoding: str = "utf-8", newline: str | None = "\n") -> None:
    """Write one text file atomically (or stage it in the active block)."""
    with Staged() as out:
        out.write_text(path, text, encoding=encoding, newline=newline)


@contextlib.contextmanager
def open_atomic(path: Path | str, mode: str = "w", encoding: str | None = "utf-8",
                newline: str | None = "\n") -> Iterator[IO]:
    """One file opened for writing; renamed into place when the block ends without an exception."""
    with Staged() as out, out.open(path, mode, encoding=encoding, newline=newline) as f:
        yield f


@contextlib.contextmanager
def atomic_path(path: Path | str) -> Iterator[Path]:
    """A temporary path for one file written by a writer that takes a path; renamed into place at the end."""
    with Staged() as out, out.path(path) as tmp:
        yield tmp
