"""One error type for everything a user can get wrong in their input, and the one way a message
shows a value the user gave.

The command line turns InputError into a single line ``error: FILE: KEY: reason`` and exit
status 2, so every check that can fail on user input raises this, never a bare ValueError.

A value echoed in a message goes through `echo` (a 1 MB enum value, a 5 000-digit number, a line
break in a key must not flood the terminal or break the one-line rule). InputError itself cuts
any part that is still too long, in its middle, so that a message that forgot `echo` stays one
readable line and keeps its end (the list of accepted values usually comes last): in a reason,
each word longer than TOKEN_LIMIT first (a pasted value), then the whole if it still exceeds its
limit (a reason the program writes may explain at length).
"""

from __future__ import annotations

ECHO_LIMIT = 60  # characters of an echoed value: a path, a unit, an enum value fit in it
PART_LIMITS = {"file": 200, "key": 120, "reason": 1200}  # characters of each part of a message: a reason the
# program writes may explain at length (the polydyne's refusal gives the stiffness and the speed that would pass,
# ~900 characters); what is cut is a value that was never echoed through `echo`


def _text(value) -> str:
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 4000:
        return echo(value)  # str() of it would raise
    return str(value)


def _cut(text: str, limit: int, head: int | None = None) -> str:
    """`text` if it fits in `limit` characters, else its head and tail around a note of the
    length (one line: control characters are shown escaped)."""
    text = text.replace("\r", "\\r").replace("\n", "\\n").replace("\x00", "\\x00")
    if len(text) <= limit:
        return text
    head = max(1, int(limit * 0.6)) if head is None else head
    tail = max(0, limit - head - 30)
    end = text[len(text) - tail:] if tail else ""
    return f"{text[:head]}...[{len(text)} characters]...{end}"


def echo(value, limit: int = ECHO_LIMIT) -> str:
    """A value as a message shows it: repr, cut to about `limit` characters with its length.
    Safe for any value: an int beyond Python's 4300-digit conversion limit is described by its
    size (repr would raise), and so is anything whose repr fails."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 4000:
        digits = int(value.bit_length() * 0.30103) + 1
        return f"<an integer of about {digits} digits>"
    try:
        text = repr(value)
    except Exception:  # noqa: BLE001 - a message must not fail on the value it reports
        return f"<a {type(value).__name__}>"
    if len(text) <= limit:
        return text.replace("\n", "\\n")
    return f"{text[:max(1, limit - 20)]}... ({len(text)} characters)"


TOKEN_LIMIT = 100  # characters of one word of a reason: longer is a value that was never echoed


def _cut_tokens(text: str) -> str:
    """Each run of non-space characters longer than TOKEN_LIMIT cut in its middle: the program's
    own prose (words and numbers) passes whole, a pasted value that forgot `echo` does not."""
    words = text.split(" ")
    if all(len(w) <= TOKEN_LIMIT for w in words):
        return text
    return " ".join(_cut(w, TOKEN_LIMIT) if len(w) > TOKEN_LIMIT else w for w in words)


class InputError(Exception):
    """Bad user input: names the file, the key (dotted path) and the reason."""

    def __init__(self, file: str, key: str, reason: str):
        self.file = _cut(_text(file), PART_LIMITS["file"])
        self.key = _cut(_text(key), PART_LIMITS["key"])
        self.reason = _cut(_cut_tokens(_text(reason)), PART_LIMITS["reason"], head=800)
        super().__init__(f"{self.file}: {self.key}: {self.reason}")


def check_port_number(port: int, option: str) -> int:
    """A TCP port given on the command line: 1 to 65535, or 0 for any free one (the system picks).
    One helper, so that every command's message is the same one line naming its option."""
    if not 0 <= port <= 65535:
        raise InputError("<command line>", option, f"must be a TCP port from 1 to 65535, or 0 for any free port, got {port}")
    return port
