"""Where the built-in scenes live, and which one is the default."""

from __future__ import annotations

import os
from pathlib import Path

DEFAULT_SCENE = "schenker1902_fig2.toml"


def scenes_dir() -> Path:
    """assets/scenes of the source tree (editable installs), else the copy shipped in the wheel
    (explorer/data is a link to assets/ in the source tree, so the wheel carries the files)."""
    package = Path(__file__).resolve().parents[1]
    for candidate in (package.parent / "assets" / "scenes", package / "data" / "scenes"):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError("no built-in scenes found (assets/scenes)")


def builtin_scenes() -> list[Path]:
    return sorted(scenes_dir().glob("*.toml"))


def find_scene(name: str | os.PathLike) -> str | os.PathLike:
    """The file a scene argument names: the path itself when something is there, else the
    built-in scene of that name as the explorer's Scene dropdown lists it ("cycloidal_demo.toml",
    or without ".toml"), else the argument unchanged (its reader then says "file not found").
    A name with a directory part is always a path: "./x.toml" never means a built-in."""
    text = os.fspath(name)
    if os.path.lexists(text) or os.sep in text or not text:
        return name
    try:
        builtins = {p.name: p for p in builtin_scenes()}
    except FileNotFoundError:
        return name
    found = builtins.get(text) or builtins.get(text + ".toml")
    return str(found) if found is not None else name


def default_scene() -> Path:
    path = scenes_dir() / DEFAULT_SCENE
    if path.exists():
        return path
    return builtin_scenes()[0]
