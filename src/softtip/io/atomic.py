"""Writing output files safely: atomically, never over an input, never leaving a partial file.

Every file softtip writes (result tables, figures, fingertip and payload TOML files,
simulated logs and their truth, Rerun recordings) goes through :class:`AtomicFile`:

* a **regular file** (or a new name) is written to a hidden temporary file in the same
  folder (``.NAME.XXXXXXXX.tmp``), flushed to disk and renamed over the destination only
  when everything succeeded: a failure, Ctrl-C, SIGTERM or SIGHUP leaves the destination
  as it was and removes the temporary file. An existing file keeps its permission bits. A
  symbolic link is followed: its target is replaced and the link stays a link.
* an existing **character device or FIFO** (``/dev/null``, ``/dev/stdout``, a named pipe)
  is never renamed over: the content is prepared in a temporary file in the system's
  temporary folder and then copied into the device. A **block device** or a socket is
  refused.
* every operating-system failure (disk full, file too large, no permission, broken pipe)
  becomes an :class:`~softtip.errors.InputError` naming the path and the system's reason.

:func:`check_distinct` refuses, before anything is computed, an output that is the same
file as an input or as another output of the same run (same path after following links,
or the same file under another name: a hard link).
"""

from __future__ import annotations

import contextlib
import errno
import io
import os
import secrets
import select
import shutil
import stat
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import IO, Any

from softtip.errors import InputError
from softtip.io.interrupt import check_interrupted, outputs_committed

__all__ = ["AtomicFile", "Outputs", "atomic_write", "atomic_write_text", "cannot_write", "check_distinct", "commit_all", "write_stdout"]

PathLike = str | os.PathLike[str]


def cannot_write(path: PathLike | str, exc: OSError) -> InputError:
    """The :class:`InputError` for an OS failure while writing ``path`` (path and the OS's reason)."""
    reason = exc.strerror or str(exc)
    if path == "standard output":
        return InputError(f"standard output: cannot write ({reason}); the output is incomplete")
    return InputError(f"{os.fspath(path)}: cannot write ({reason}); nothing was written there")


def _identity(path: str) -> tuple[str, tuple[int, int] | None]:
    """(real path, (device, inode) when the file exists)."""
    real = os.path.realpath(path)
    try:
        st = os.stat(real)
    except OSError:
        return real, None
    return real, (st.st_dev, st.st_ino)


def check_distinct(inputs: Iterable[tuple[str, PathLike | None]], outputs: Iterable[tuple[str, PathLike | None]]) -> None:
    """Refuse an output that is an input or another output of the same run.

    Parameters
    ----------
    inputs, outputs : iterable of (label, path)
        ``label`` names the option (``"INPUT"``, ``"-o"``, ``"--plot"``); ``path`` may be
        ``None`` or ``"-"`` (standard input/output), which are skipped. An input that is a
        directory (a ROS bag) also protects every file inside it.

    Raises
    ------
    InputError
        Naming both options and both paths. Exit code 2 on the command line.
    """
    seen: list[tuple[str, str, str, tuple[int, int] | None, bool]] = []
    for label, path in inputs:
        if path is None or os.fspath(path) == "-":
            continue
        p = os.fspath(path)
        real, ident = _identity(p)
        seen.append((label, p, real, ident, os.path.isdir(real)))
    n_inputs = len(seen)
    for label, path in outputs:
        if path is None or os.fspath(path) == "-":
            continue
        p = os.fspath(path)
        real, ident = _identity(p)
        for k, (other_label, other, other_real, other_ident, is_dir) in enumerate(seen):
            same = real == other_real or (ident is not None and ident == other_ident)
            inside = is_dir and k < n_inputs and real.startswith(other_real.rstrip(os.sep) + os.sep)
            if same or inside:
                what = "input" if k < n_inputs else "output"
                where = "inside the" if inside and not same else "the same file as the"
                raise InputError(
                    f"{label} {p}: is {where} {what} {other_label} {other}; refusing to overwrite it "
                    "(give another output file name)"
                )
        seen.append((label, p, real, ident, False))


class AtomicFile:
    """One output file, written to a temporary file and put in place by :meth:`commit`.

    Parameters
    ----------
    path : str or path-like
        The destination.

    Attributes
    ----------
    path : str
        The destination as given.
    tmp : pathlib.Path
        Where to write (keeps the destination's suffix, so writers that pick a format from
        the name, e.g. matplotlib, still do).

    Raises
    ------
    InputError
        The destination is a directory, a block device or a socket, or the temporary file
        cannot be created (missing folder, no permission).

    Notes
    -----
    Use as a context manager: leaving the ``with`` block by an exception (including
    ``KeyboardInterrupt``) removes the temporary file. :meth:`commit` may be called inside
    the block, or later (several outputs committed together), followed by :meth:`discard`
    on failure.
    """

    def __init__(self, path: PathLike) -> None:
        self.path = os.fspath(path)
        if not self.path:
            raise InputError("'': an empty file name; expected a file name for the output")
        target = os.path.realpath(self.path)  # a symlink's target is replaced, not the link
        try:
            st = os.stat(self.path)  # follows links, also /dev/stdout -> /proc/self/fd/1 -> pipe:[...]
        except FileNotFoundError:
            st = None
        except OSError as exc:
            raise cannot_write(self.path, exc) from None
        self._device = st is not None and not stat.S_ISREG(st.st_mode)
        if self._device:
            target = self.path  # a pipe's "real path" (pipe:[123]) cannot be opened; the name can
        if st is not None:
            if stat.S_ISDIR(st.st_mode):
                raise InputError(f"{self.path}: is a directory; expected a file name for the output")
            if stat.S_ISBLK(st.st_mode) or stat.S_ISSOCK(st.st_mode):
                kind = "a block device" if stat.S_ISBLK(st.st_mode) else "a socket"
                raise InputError(f"{self.path}: is {kind}; refusing to write there (expected a file name)")
        self._target = target
        self._mode = None if st is None or self._device else stat.S_IMODE(st.st_mode)
        directory, name = os.path.split(target)
        suffix = Path(name).suffix
        if self._device:
            directory = tempfile.gettempdir()
        self.tmp = Path(directory) / f".{name}.{secrets.token_hex(4)}.tmp{suffix}"
        try:
            # 0o666: the umask decides the mode, as a plain open(path, "w") would
            fd = os.open(self.tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666 if self._mode is None else 0o600)
        except OSError as exc:
            raise cannot_write(self.path, exc) from None
        os.close(fd)
        self._done = False

    @property
    def is_device(self) -> bool:
        """The destination is an existing character device or FIFO (written into, not renamed over)."""
        return self._device

    def open(self, mode: str = "w", **kwargs: Any) -> IO[Any]:
        """Open the temporary file (text mode: UTF-8, no newline translation unless given).

        Written from the start (``"w"``, ``"wb"``) into a file to be renamed into place, the
        kernel writes its pages back and drops them behind the writer (:class:`_WriteBehind`).
        """
        if "b" not in mode:
            kwargs.setdefault("encoding", "utf-8")
            kwargs.setdefault("newline", "")
        text_kwargs = {"encoding", "errors", "newline"} if mode == "w" else set()
        if self._device or mode not in ("w", "wb") or not set(kwargs) <= text_kwargs or not hasattr(os, "posix_fadvise"):
            return open(self.tmp, mode, **kwargs)
        binary = io.BufferedWriter(_WriteBehind(self.tmp))
        if mode == "wb":
            return binary
        try:
            text = io.TextIOWrapper(binary, **kwargs)
        except BaseException:
            binary.close()
            raise
        text.mode = mode  # as open() sets it
        return text

    def commit(self) -> None:
        """Put the content in place (rename, or copy into a device); the temporary file goes."""
        if self._done:
            return
        try:
            if self._device:
                self._copy_into_device()
            else:
                self._prepare()
                os.replace(self.tmp, self._target)
        except OSError as exc:
            self.discard()
            raise cannot_write(self.path, exc) from None
        self._done = True

    def _copy_into_device(self) -> None:
        """Copy the content into a character device or FIFO.

        A FIFO waits for its reader, as ``cat > FIFO`` does, but in short steps that let
        Ctrl-C, SIGTERM and SIGHUP through (the kernel may hand a signal to another thread,
        which would not interrupt a blocking open or write of the main one).
        """
        if not stat.S_ISFIFO(os.stat(self._target).st_mode):
            with open(self.tmp, "rb") as src, open(self._target, "wb") as dst:
                shutil.copyfileobj(src, dst, 1 << 20)
            os.unlink(self.tmp)
            self._done = True
            return
        while True:
            try:
                fd = os.open(self._target, os.O_WRONLY | os.O_NONBLOCK)
                break
            except OSError as exc:
                if exc.errno != errno.ENXIO:  # ENXIO: no reader yet
                    raise
                check_interrupted()
                time.sleep(0.05)
        try:
            with open(self.tmp, "rb") as src:
                while chunk := src.read(1 << 16):
                    view = memoryview(chunk)
                    while view:
                        check_interrupted()
                        select.select([], [fd], [], 0.1)
                        try:
                            view = view[os.write(fd, view) :]
                        except BlockingIOError:
                            continue
        finally:
            os.close(fd)
        os.unlink(self.tmp)
        self._done = True

    def _prepare(self) -> None:
        """Sync the temporary file and give it the destination's mode (before the rename)."""
        with open(self.tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        if self._mode is not None:
            os.chmod(self.tmp, self._mode)

    def discard(self) -> None:
        """Remove the temporary file (the destination is untouched). Safe to call twice."""
        self._done = True
        with contextlib.suppress(OSError):
            os.unlink(self.tmp)

    def __enter__(self) -> AtomicFile:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            self.discard()
            if isinstance(exc, OSError) and not isinstance(exc, InputError):
                raise cannot_write(self.path, exc) from None


#: Bytes written between two hand-overs to the kernel's writeback (:class:`_WriteBehind`).
WRITE_BEHIND_BYTES = 64 << 20


class _WriteBehind(io.FileIO):
    """A file written from the start whose pages the kernel writes back and drops behind the
    writer: every :data:`WRITE_BEHIND_BYTES`, the range written since the last hand-over is
    handed to writeback, and the range handed over the time before (written back by then, or
    kept cached where it is not) is dropped from the page cache (``posix_fadvise(POSIX_FADV_DONTNEED)``, which on Linux starts
    the writeback of dirty pages without waiting and drops clean ones).

    A table of gigabytes otherwise fills the page cache with dirty pages the commit's ``fsync``
    then writes at once, and takes that many new pages, which on some machines cost most of the
    write (``benchmarks/bench_write_behind.py``; the performance page has the figures). Files
    below the step are not advised at all. The file is written from its start, in order (the
    ranges advised are the bytes written so far). The advice changes no byte: the commit still
    syncs the whole file before the rename.
    """

    def __init__(self, path: PathLike) -> None:
        super().__init__(path, "w")
        self._end = 0  # bytes written
        self._handed = 0  # the end of the range handed to writeback
        self._dropped = 0  # the end of the range dropped
        self._advise = True

    def write(self, b: Any) -> int:
        n = super().write(b)
        self._end += n
        if self._advise and self._end - self._handed >= WRITE_BEHIND_BYTES:
            fd = self.fileno()
            try:
                if self._handed > self._dropped:  # (a length of 0 would mean "to the end of the file")
                    os.posix_fadvise(fd, self._dropped, self._handed - self._dropped, os.POSIX_FADV_DONTNEED)
                os.posix_fadvise(fd, self._handed, self._end - self._handed, os.POSIX_FADV_DONTNEED)
            except OSError:  # advice only: a file system that takes none is written as any other
                self._advise = False
            self._dropped, self._handed = self._handed, self._end
        return n


def partial_dir(dest: PathLike) -> Path:
    """A new hidden directory beside ``dest`` to write an output directory in, then rename into place.

    Unlike :func:`tempfile.mkdtemp` (mode 0700) its mode follows the umask, as ``mkdir``'s
    would, so the renamed directory has the permissions the user expects.

    Raises
    ------
    OSError
        The parent directory does not exist or is not writable.
    """
    dest = Path(dest)
    parent = dest.parent if str(dest.parent) else Path(".")
    while True:
        tmp = parent / f".{dest.name}.{secrets.token_hex(4)}.partial"
        try:
            os.mkdir(tmp, 0o777)
            return tmp
        except FileExistsError:
            continue


class Outputs:
    """Every output of one run, staged and then committed together: all appear, or none.

    Files (:meth:`file`: result tables, figures, TOML files, Rerun recordings) and output
    paths written by another writer (:meth:`path`: a bag, a directory) are prepared beside
    their destinations. :meth:`commit` first copies into devices and FIFOs (``/dev/stdout``,
    a named pipe: what can block or fail), then renames the staged files and directories
    into place, keeping a hard link of each file it replaces until all renames succeeded;
    a failure restores the replaced files, so every file that existed before the run is
    byte-identical after a failed run. Leaving the ``with`` block by an exception (an
    error, Ctrl-C, SIGTERM, SIGHUP) discards everything staged; leaving it normally
    commits what :meth:`commit` has not.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with Outputs() as out:
    ...     with out.file(d / "a.txt").open() as fh:
    ...         _ = fh.write("a")
    ...     with out.file(d / "b.txt").open() as fh:
    ...         _ = fh.write("b")
    >>> sorted(p.name for p in d.iterdir())
    ['a.txt', 'b.txt']
    """

    def __init__(self) -> None:
        self._files: list[AtomicFile] = []
        self._paths: list[tuple[str, Path, Path]] = []  # (destination, staged path, its staging folder)
        self._done = False

    def file(self, path: PathLike) -> AtomicFile:
        """Stage one output file; write to the returned :class:`AtomicFile` (``.open()`` or ``.tmp``)."""
        af = AtomicFile(path)
        self._files.append(af)
        return af

    def get(self, path: PathLike | None) -> AtomicFile | None:
        """The staged file for ``path`` (as given to :meth:`file`), or None."""
        if path is None:
            return None
        return next((f for f in self._files if f.path == os.fspath(path)), None)

    def path(self, dest: PathLike) -> Path:
        """Stage an output a writer creates itself (a bag directory or file), which must not exist yet.

        Returns
        -------
        pathlib.Path
            Where to create it: a new name, with the destination's file name, in a hidden
            folder beside ``dest``; moved to ``dest`` by :meth:`commit`.

        Raises
        ------
        InputError
            ``dest`` exists, or its folder does not exist or is not writable.
        """
        dest_s = os.fspath(dest)
        if not dest_s:
            raise InputError("'': an empty name; expected a name for the output")
        if os.path.lexists(dest_s):
            raise InputError(f"{dest_s}: exists already; expected a new name for the output")
        try:
            folder = partial_dir(dest_s)
        except OSError as exc:
            raise cannot_write(dest_s, exc) from None
        staged = folder / Path(dest_s).name
        self._paths.append((dest_s, staged, folder))
        return staged

    def commit(self) -> None:
        """Put every staged output in place, or none (see the class notes).

        Raises
        ------
        InputError
            An output could not be put in place (naming it and the system's reason);
            nothing staged stays behind and every replaced file is restored.
        """
        if self._done:
            return
        self._done = True
        try:
            check_interrupted()  # a signal some library swallowed: never commit after one
            for f in self._files:  # devices and pipes first: they can block or fail
                if f.is_device:
                    f.commit()
            for f in self._files:
                if not f.is_device:
                    try:
                        f._prepare()
                    except OSError as exc:
                        raise cannot_write(f.path, exc) from None
        except BaseException:
            self.discard()
            raise
        backups: list[tuple[str, str | None]] = []  # (target, its backup or None: a new file)
        try:
            for f in self._files:
                if f.is_device:
                    continue
                backup = None
                if os.path.lexists(f._target):
                    backup = f"{f._target}.{secrets.token_hex(4)}.bak"
                    try:
                        os.link(f._target, backup)
                    except OSError:
                        backup = None  # no hard links here: the rename is still atomic
                try:
                    os.replace(f.tmp, f._target)
                except OSError as exc:
                    if backup is not None:
                        os.unlink(backup)
                    raise cannot_write(f.path, exc) from None
                f._done = True
                backups.append((f._target, backup))
            for dest, staged, _ in self._paths:
                if os.path.lexists(dest):
                    raise InputError(f"{dest}: appeared during the run; expected a new name for the output")
                try:
                    os.rename(staged, dest)
                except OSError as exc:
                    raise cannot_write(dest, exc) from None
                backups.append((dest, "dir"))
        except BaseException:
            for target, backup in reversed(backups):
                with contextlib.suppress(OSError):
                    if backup == "dir":
                        _remove(target)
                    elif backup is None:
                        os.unlink(target)
                    else:
                        os.replace(backup, target)
            self.discard()
            raise
        outputs_committed()  # a signal from here on does not turn the finished run into a failed one
        for _target, backup in backups:
            if backup not in (None, "dir"):
                with contextlib.suppress(OSError):
                    os.unlink(backup)
        self.discard()  # the staging folders (empty by now)

    def discard(self) -> None:
        """Remove everything staged (destinations untouched). Safe to call twice."""
        self._done = True
        for f in self._files:
            f.discard()
        for _, _, folder in self._paths:
            shutil.rmtree(folder, ignore_errors=True)

    def __enter__(self) -> Outputs:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            self.discard()
        else:
            self.commit()


def _remove(path: str) -> None:
    if os.path.isdir(path) and not os.path.islink(path):
        shutil.rmtree(path, ignore_errors=True)
    else:
        os.unlink(path)


def commit_all(files: Iterable[AtomicFile]) -> None:
    """Put several outputs in place: devices and pipes first (they can block or fail), then the renames.

    A failure (or an interrupt) while writing into a device leaves every regular file
    untouched; a failing rename restores the files already replaced (:class:`Outputs`).
    """
    transaction = Outputs()
    transaction._files = list(files)
    transaction.commit()


@contextlib.contextmanager
def atomic_write(path: PathLike, mode: str = "w", **kwargs: Any) -> Iterator[IO[Any]]:
    """Open ``path`` for writing, atomically: the content appears only if the block succeeds.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "out.txt"
    >>> with atomic_write(path) as fh:
    ...     _ = fh.write("hello\\n")
    >>> path.read_text()
    'hello\\n'
    """
    with AtomicFile(path) as af:
        try:
            with af.open(mode, **kwargs) as fh:
                yield fh
        except OSError as exc:
            raise cannot_write(path, exc) from None
        af.commit()


def atomic_write_text(path: PathLike, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically (see :class:`AtomicFile`)."""
    with atomic_write(path) as fh:
        fh.write(text)


def write_stdout(write: Callable[[IO[str]], None] | str) -> None:
    """Write to standard output; a full device or a closed pipe becomes an :class:`InputError`.

    Parameters
    ----------
    write : str or callable
        The text, or a function that writes to the stream it is given.
    """
    try:
        if isinstance(write, str):
            sys.stdout.write(write)
        else:
            write(sys.stdout)
        sys.stdout.flush()
    except OSError as exc:
        silence_stdout()
        raise cannot_write("standard output", exc) from None


def silence_stdout() -> None:
    """Point file descriptor 1 at the null device, so Python's final flush cannot fail again."""
    with contextlib.suppress(OSError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)

