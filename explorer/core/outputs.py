"""Every file a command writes (CSV, JSON, PNG, text, .rrd) goes through here, so that one set of
rules decides what a path the user named may become.

- A regular file, or a name that is not there yet: written to a hidden temporary file in the same
  directory and renamed over the target when complete, so a crash or a full disk never leaves a
  half-written file under that name. A new file gets the mode any new file gets (0666 less the
  umask); a file that is replaced keeps its mode (and, where permitted, its owner and group).
- A symbolic link: followed. Its target is written as above and the link stays a link; a link
  that points nowhere yet creates its target, as the shell's `>` does.
- `-`, /dev/stdout, /dev/stderr, /dev/fd/N, a terminal, /dev/null, a FIFO (character devices,
  FIFOs and the process's own file descriptors): written directly, in order, with no temporary and no
  rename. A rename would put a regular file where the device or pipe was; writing through is what
  `cmd -o /dev/stdout | next` means. Such targets are opened for appending, so `>> log` keeps its
  log, and a FIFO blocks until someone reads it, as it does for any writer.
- Directories, block devices, sockets: refused before any work; so is a file that its mode makes
  read-only for this user, as the shell's `>` would (root may write anything, here as there).

`distinct_outputs` refuses an output file that is the same file as an input of the command (its
scene) or as another of its outputs, before any work.

`check_output` applies these rules before anything is computed, including a real probe that the
directory accepts a new file (as root, or on a read-only file system, the permission bits say
nothing): a wrong path costs one line and exit status 2, not a simulation.

Several outputs of one command are all or none (`all_or_none`): inside the block every file is
written to its temporary and every device or pipe to a temporary of its own; when the block ends
without an error the devices and pipes are written first (they are the outputs that can still
fail: /dev/full passes every check and takes no byte), then the files are renamed into place.
Any failure, a stop signal included, removes every temporary and publishes nothing, so a table
is never left without its plot. (A device or pipe written before another one failed keeps what
it got: bytes sent cannot be taken back.)
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import re
import shutil
import stat
import tempfile
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Iterable, Iterator

from .errors import InputError

NEW_FILE_MODE = 0o666  # before the umask, as open(2) and the shell create files
_FD_DIR = re.compile(r"/proc/(self|thread-self|\d+)(/task/\d+)?/fd")
_MAX_LINK_HOPS = 40  # the kernel's own limit on symlinks in one lookup


HELP = """\
Output files appear only when complete: a temporary file beside the target, renamed over it (a
new file gets 0666 less the umask, a replaced file keeps its mode; a symlink is followed and its
target written). `-` (stdout), /dev/stdout, /dev/null, terminals and FIFOs are written directly,
no temporary.
Directories, block devices, sockets, read-only files and directories that take no new file are
refused before any work (exit status 2); so is an output that is the same file as an input (the
scene) or as another output of the same command.
"""


@dataclass(frozen=True)
class Output:
    """A checked output: `name` as the user wrote it, `option` the flag that named it, `target`
    where the bytes go (links followed), `direct` True for devices, FIFOs and /dev/stdout."""

    name: str
    option: str
    target: Path
    direct: bool

    def error(self, reason: str) -> InputError:
        return InputError(self.name, self.option, reason)

    def is_stdout(self) -> bool:
        """True when this output is the process's standard output (`-o /dev/stdout`, or a
        FIFO or file that stdout is also connected to): messages then belong on stderr."""
        if not self.direct:
            return False
        try:
            a, b = os.stat(self.target), os.fstat(1)
        except OSError:
            return False
        return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def _through_fd_link(path: str) -> bool:
    """True when `path` names one of the process's file descriptors (/dev/stdout, /dev/fd/1,
    /proc/self/fd/1, or a link to one). Those are magic links: following them can land on a
    regular file (stdout redirected with `>`), which must still be written through, not replaced."""
    current = os.path.abspath(path)
    for _ in range(_MAX_LINK_HOPS):
        parent = os.path.realpath(os.path.dirname(current))
        if _FD_DIR.fullmatch(parent):
            return True
        here = os.path.join(parent, os.path.basename(current))
        if not os.path.islink(here):
            return False
        current = os.path.join(parent, os.readlink(here))
    return False


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "a directory"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"


def _probe_directory(out: Output, directory: Path) -> None:
    """Create and remove an empty file where the temporary will go: the only test that sees a
    read-only mount, an immutable directory or an exhausted inode table, also as root."""
    # not named after the target: the `.NAME.*` temporaries mean a write under way
    probe = directory / f".explorer-probe.{uuid.uuid4().hex[:12]}"
    try:
        fd = os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError as exc:
        raise out.error(f"directory {directory} is not writable ({exc.strerror or exc})") from None
    os.close(fd)
    os.unlink(probe)


def check_output(path: str | os.PathLike, option: str, suffix: str | None = None) -> Output:
    """Check an output path the user named, before any work (see the module docstring).
    `suffix` (e.g. ".rrd") is required of files, not of devices and pipes."""
    name = os.fspath(path)
    if not name:
        raise InputError("<command line>", option, "empty file name")
    if "\x00" in name:
        raise InputError("<command line>", option, "a file name cannot contain a NUL byte")
    if name == "-" or _through_fd_link(name):
        where = "/dev/stdout" if name == "-" else name  # "-": standard output, as for most tools
        out = Output(name, option, Path(where), direct=True)
        if not os.access(where, os.W_OK):
            raise out.error("is not writable (is that file descriptor open?)")
        return out
    try:
        st = os.stat(name)  # follows links
    except (FileNotFoundError, NotADirectoryError):  # the directory checks below say which
        st = None
    except OSError as exc:
        raise InputError(name, option, f"cannot use it: {exc.strerror or exc}") from None
    if st is not None and (stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode)):
        out = Output(name, option, Path(name), direct=True)
        if not os.access(name, os.W_OK):
            raise out.error("is not writable")
        return out
    if suffix is not None and Path(name).suffix.lower() != suffix:
        raise InputError(name, option, f"the file name must end in {suffix}")
    if st is not None and stat.S_ISDIR(st.st_mode):
        raise InputError(name, option, "is a directory, not a file name")
    if st is not None and not stat.S_ISREG(st.st_mode):
        raise InputError(name, option, f"is {_kind(st.st_mode)}; only regular files, character devices "
                         "and FIFOs are written")
    if st is not None and not os.access(name, os.W_OK):
        # as the shell's `>` would: the rename could replace it, but its mode says keep it
        raise InputError(name, option, f"is read-only (mode {stat.S_IMODE(st.st_mode):04o})")
    target = Path(os.path.realpath(name))
    out = Output(name, option, target, direct=False)
    directory = target.parent
    if not directory.is_dir():
        raise out.error(f"{directory} is not a directory" if directory.exists()
                        else f"directory {directory} does not exist")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise out.error(f"directory {directory} is not writable")
    _probe_directory(out, directory)
    return out


def _same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """True when the two paths name one file: the same inode where both exist (links, hard links
    and `..` all resolved by the kernel), else the same resolved path."""
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them is not there yet
        return os.path.realpath(a) == os.path.realpath(b)


def distinct_outputs(outputs: Iterable[Output | None], inputs: Iterable[str | os.PathLike | None] = ()) -> None:
    """Refuse, before any work, an output file that is the same file as one of the command's
    inputs (the scene it reads) or as another of its outputs: the rename would replace the input,
    or one output the other. Devices, FIFOs and standard output are written through, not
    replaced, and are not compared (`-o - --summary -` writes both, in order)."""
    files = [o for o in outputs if o is not None and not o.direct]
    sources = [os.fspath(p) for p in inputs if p is not None and os.fspath(p) not in ("", "-", "<memory>")]
    for i, out in enumerate(files):
        for src in sources:
            if os.path.exists(src) and _same_file(out.target, src):
                raise out.error(f"is the input file {src}: writing it would replace the input; choose another name")
        for other in files[:i]:
            if _same_file(out.target, other.target):
                raise out.error(f"is the same file as {other.option} {other.name}: choose another name for one of them")


def as_output(path_or_output, option: str = "output") -> Output:
    """An Output from one (returned as is) or from a path, checked now."""
    return path_or_output if isinstance(path_or_output, Output) else check_output(path_or_output, option)


def _final_mode(target: Path) -> tuple[int | None, int, int]:
    """(mode, uid, gid) of the file being replaced, or (None, -1, -1) for a new one."""
    try:
        st = os.stat(target)
    except FileNotFoundError:
        return None, -1, -1
    return stat.S_IMODE(st.st_mode), st.st_uid, st.st_gid


def _create_temporary(target: Path) -> tuple[int, Path, tuple[int | None, int, int]]:
    """An open, new, hidden file beside `target`. A new target's temporary is created with the
    mode a new file gets, so the umask and the directory's default ACL apply as for any file; a
    replacement's is created private and given the old file's mode before the rename."""
    keep = _final_mode(target)
    for _ in range(100):
        tmp = target.parent / f".{target.name}.{uuid.uuid4().hex[:12]}.part"
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0),
                         NEW_FILE_MODE if keep[0] is None else 0o600)
            return fd, tmp, keep
        except FileExistsError:
            continue
    raise FileExistsError(f"no free temporary name beside {target}")


def _publish(fd: int, tmp: Path, target: Path, keep: tuple[int | None, int, int]) -> None:
    mode, uid, gid = keep
    if mode is not None:
        with contextlib.suppress(PermissionError):  # only root may give a file to someone else
            os.fchown(fd, uid, gid)
        os.fchmod(fd, mode)  # after the chown, which clears set-id bits
    os.replace(tmp, target)


@dataclass(frozen=True)
class _Staged:
    """An output written to its temporary inside all_or_none, published when the block ends."""

    out: Output
    tmp: Path
    keep: tuple[int | None, int, int] | None = None  # a file's mode etc. to keep (None: a direct output)
    scratch: Path | None = None  # a direct output's temporary directory


_pending: contextvars.ContextVar[list[_Staged] | None] = contextvars.ContextVar("explorer_outputs", default=None)


def _stage(out: Output) -> _Staged:
    """A temporary for `out`, registered with the open all_or_none block before anything is
    written to it (so that a failure or a signal finds it and removes it)."""
    if out.direct:
        scratch = Path(tempfile.mkdtemp(prefix=".explorer-out."))
        item = _Staged(out, scratch / "out", None, scratch)
    else:
        fd, tmp, keep = _create_temporary(out.target)
        os.close(fd)
        item = _Staged(out, tmp, keep)
    pending = _pending.get()
    assert pending is not None
    pending.append(item)
    return item


def _discard(staged: list[_Staged]) -> None:
    for item in staged:
        if item.scratch is not None:
            shutil.rmtree(item.scratch, ignore_errors=True)
        else:
            item.tmp.unlink(missing_ok=True)


def _commit(staged: list[_Staged]) -> None:
    for item in staged:  # devices and pipes first: the outputs that can still fail
        if item.keep is not None:
            continue
        try:
            with open(item.tmp, "rb") as src:
                fd = os.open(item.out.target, os.O_WRONLY | os.O_APPEND | getattr(os, "O_CLOEXEC", 0))
                with os.fdopen(fd, "wb") as dst:
                    shutil.copyfileobj(src, dst, 1 << 20)
        except BrokenPipeError:
            pass  # the reader has gone (`| head`): it has what it wanted, as for any filter
        except OSError as exc:
            raise item.out.error(f"cannot write: {exc.strerror or exc}") from None
    for item in staged:
        if item.keep is not None:
            try:
                with open(item.tmp, "rb+") as handle:
                    _publish(handle.fileno(), item.tmp, item.out.target, item.keep)
            except OSError as exc:
                raise item.out.error(f"cannot write: {exc.strerror or exc}") from None
    _discard([item for item in staged if item.scratch is not None])


@contextlib.contextmanager
def all_or_none() -> Iterator[None]:
    """Every output written inside the block (write_output, open_output, output_path) is published
    when the block ends without an error, and none if anything fails (module docstring). Nested
    blocks join the outermost."""
    if _pending.get() is not None:
        yield
        return
    staged: list[_Staged] = []
    token = _pending.set(staged)
    try:
        yield
        _pending.reset(token)
        token = None
        _commit(staged)
    except BaseException:
        if token is not None:
            _pending.reset(token)
        _discard(staged)
        raise


@contextlib.contextmanager
def open_output(out: Output, binary: bool = False) -> Iterator[IO]:
    """A handle to write `out` through; on success the file is complete under its name (renamed
    into place, or written through for a device or pipe; inside all_or_none, when the block ends);
    on failure no temporary is left."""
    mode = "wb" if binary else "w"
    text_args = {} if binary else {"encoding": "utf-8", "newline": ""}
    if _pending.get() is not None:
        item = _stage(out)
        with open(item.tmp, mode, **text_args) as handle:
            yield handle
        return
    if out.direct:
        fd = os.open(out.target, os.O_WRONLY | os.O_APPEND | getattr(os, "O_CLOEXEC", 0))
        with os.fdopen(fd, mode, **text_args) as handle:
            yield handle
        return
    fd, tmp, keep = _create_temporary(out.target)
    try:
        with os.fdopen(fd, mode, closefd=False, **text_args) as handle:
            yield handle
        _publish(fd, tmp, out.target, keep)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    finally:
        os.close(fd)


def write_output(out, data: str | bytes | Iterable[str] | Iterable[bytes], option: str = "output") -> None:
    """Write text or bytes (or an iterable of pieces, written one after the other) to `out`."""
    out = as_output(out, option)
    pieces = [data] if isinstance(data, (str, bytes, bytearray)) else data
    it = iter(pieces)
    first = next(it, "")
    try:
        with open_output(out, binary=isinstance(first, (bytes, bytearray))) as handle:
            handle.write(first)
            for piece in it:
                handle.write(piece)
    except BrokenPipeError:
        if not out.direct:
            raise
        # the reader has gone (`-o /dev/stdout | head`): it has what it wanted, as for any filter


@contextlib.contextmanager
def output_path(out: Output, work_dir: Path | None = None) -> Iterator[Path]:
    """A file name for a writer that needs one (rerun's file sink, `rerun rrd merge`): yields a
    fresh temporary path; when the block ends without an error, its content is published to `out`
    (renamed into place, or copied into a device or pipe). `work_dir` holds the temporary for a
    direct output (default: the system's temporary directory). Inside all_or_none the content is
    published when that block ends."""
    if _pending.get() is not None:
        yield _stage(out).tmp
        return
    if out.direct:
        scratch = Path(tempfile.mkdtemp(prefix=".explorer-out.", dir=work_dir))
        try:
            tmp = scratch / "out"
            yield tmp
            with open(tmp, "rb") as src, open_output(out, binary=True) as dst:
                shutil.copyfileobj(src, dst, 1 << 20)
        finally:
            shutil.rmtree(scratch, ignore_errors=True)
        return
    fd, tmp, keep = _create_temporary(out.target)
    try:
        yield tmp
        # the writer may have replaced the empty file we reserved: set the mode on what is there
        with open(tmp, "rb+") as handle:
            _publish(handle.fileno(), tmp, out.target, keep)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    finally:
        os.close(fd)


def write_checked(out, data, option: str = "output") -> None:
    """write_output for a command: a failure to write (a full disk, a race with the checks) is one
    line naming the output and its option, nothing left behind."""
    out = as_output(out, option)
    try:
        write_output(out, data)
    except OSError as exc:
        raise out.error(f"cannot write: {exc.strerror or exc}") from None
