"""One error type for everything a user can get wrong in their input.

The command line turns it into a single line ``error: FILE: KEY: reason`` and exit status 2,
so every check that can fail on user input raises this, never a bare ValueError.
"""

from __future__ import annotations


class InputError(Exception):
    """Bad user input: names the file, the key (dotted path) and the reason."""

    def __init__(self, file: str, key: str, reason: str):
        self.file = str(file)
        self.key = str(key)
        self.reason = str(reason)
        super().__init__(f"{self.file}: {self.key}: {self.reason}")
