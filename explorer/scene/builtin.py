"""Where the built-in scenes live, and which one is the default."""

from __future__ import annotations

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


def default_scene() -> Path:
    path = scenes_dir() / DEFAULT_SCENE
    if path.exists():
        return path
    return builtin_scenes()[0]
