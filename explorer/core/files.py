"""Reading a file a user names (a scene, a lift table, a contour): regular files only, bounded.

A FIFO would block `open` for ever, /dev/zero or /dev/urandom would be read until memory runs
out, so the file is checked with stat before it is opened, opened non-blocking (it could be
swapped for a FIFO between the two calls) and checked again on the open descriptor, and never
more than the limit is read. The errors name the file and the problem, never its content.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from .errors import InputError

MAX_DATA_FILE_BYTES = 50 * 1024 * 1024  # a lift table or a contour: 50 MB is millions of rows
MAX_SCENE_FILE_BYTES = 10 * 1024 * 1024  # a scene is a page of TOML


def data_folder(fields) -> Path:
    """The folder a scene's relative data paths ([lift] file, [cam] file) are taken from: the
    folder of the scene file as found (`folder`, set by load_scene: a built-in scene given by its
    name lives in the package, not in the working directory), else the folder of `source`, else
    the working directory (a scene from memory)."""
    folder = fields.get("folder") or ""
    if folder:
        return Path(folder)
    source = fields.get("source", "<memory>")
    return Path(source).parent if source != "<memory>" else Path.cwd()


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a plain file"


def check_path(path, *, file: str, key: str, prefix: str = "") -> None:
    """A path the user named must be one the system can look up: no NUL byte (os functions raise
    ValueError on it, which is no message), not empty."""
    text = os.fspath(path)
    if isinstance(text, bytes):
        text = text.decode("utf-8", "surrogateescape")
    if "\x00" in text:
        raise InputError(file, key, f"{prefix}a file name cannot contain a NUL byte")
    if not text:
        raise InputError(file, key, f"{prefix}empty file name")


def check_regular(path, *, file: str, key: str, prefix: str = "", limit: int | None = None) -> os.stat_result:
    """stat of `path` if it is a regular file (within `limit` bytes), else InputError."""
    check_path(path, file=file, key=key, prefix=prefix)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise InputError(file, key, f"{prefix}file not found") from None
    except OSError as exc:
        raise InputError(file, key, f"{prefix}cannot read: {exc.strerror or type(exc).__name__}") from None
    _check_stat(info, file=file, key=key, prefix=prefix, limit=limit)
    return info


def _check_stat(info: os.stat_result, *, file: str, key: str, prefix: str, limit: int | None) -> None:
    if not stat.S_ISREG(info.st_mode):
        raise InputError(file, key, f"{prefix}not a regular file ({_kind(info.st_mode)})")
    if limit is not None and info.st_size > limit:
        raise InputError(file, key, f"{prefix}file too large: {info.st_size} bytes, at most {limit} "
                         f"({limit // (1024 * 1024)} MB)")


def read_regular(path, *, file: str, key: str, prefix: str = "", limit: int = MAX_DATA_FILE_BYTES) -> bytes:
    """The bytes of a regular file of at most `limit` bytes, or InputError (never blocks)."""
    check_regular(path, file=file, key=key, prefix=prefix, limit=limit)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise InputError(file, key, f"{prefix}cannot read: {exc.strerror or type(exc).__name__}") from None
    try:
        _check_stat(os.fstat(fd), file=file, key=key, prefix=prefix, limit=limit)
        chunks, size = [], 0
        while True:  # a file that grows while it is read still stops at the limit
            chunk = os.read(fd, min(1 << 20, limit + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
            if size > limit:
                raise InputError(file, key, f"{prefix}file too large: more than {limit} bytes")
        return b"".join(chunks)
    except OSError as exc:
        raise InputError(file, key, f"{prefix}cannot read: {exc.strerror or type(exc).__name__}") from None
    finally:
        os.close(fd)


def read_text(path, *, file: str, key: str, prefix: str = "", limit: int = MAX_DATA_FILE_BYTES) -> str:
    """read_regular decoded as UTF-8, or InputError."""
    data = read_regular(path, file=file, key=key, prefix=prefix, limit=limit)
    try:
        # "utf-8-sig": a leading byte-order mark (Windows editors, Excel's CSV) is dropped, not read
        # as the first character of the first line
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(file, key, f"{prefix}not a UTF-8 text file") from None
