"""Every built-in scene has its picture from the real browser explorer (issue #28), and the
README's table of built-in scenes shows each one: a scene added without its picture, or left
out of the table, fails here. The pictures are taken by docs/_tools/scene_pictures.py."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from explorer.scene.builtin import builtin_scenes

ROOT = Path(__file__).resolve().parents[1]
PICTURES = ROOT / "docs" / "images" / "scenes"
PNG = b"\x89PNG\r\n\x1a\n"
TOTAL_BYTES = 2 * 2**20  # the whole set stays small in the repository


def _scenes_section() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    match = re.search(r"^## Built-in scenes\n(.*?)(?=^## )", text, flags=re.S | re.M)
    assert match, "README.md has no '## Built-in scenes' section"
    return match.group(1)


def _table_rows() -> dict[str, str]:
    """scene file name -> its row in the README's table (first cell)."""
    rows = {}
    for line in _scenes_section().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")] if line.startswith("|") else []
        names = re.findall(r"`([\w.-]+\.toml)`", cells[0]) if cells else []
        for name in names:
            rows[name] = line
    return rows


@pytest.mark.parametrize("scene", builtin_scenes(), ids=lambda p: p.stem)
def test_every_built_in_scene_has_its_picture_in_the_readme_table(scene):
    picture = PICTURES / f"{scene.stem}.png"
    assert picture.is_file(), f"no picture of {scene.name}: run docs/_tools/scene_pictures.py {scene.stem}"
    assert picture.read_bytes()[:8] == PNG
    row = _table_rows().get(scene.name)
    assert row is not None, f"README.md's table of built-in scenes has no row for {scene.name}"
    assert f"](docs/images/scenes/{scene.stem}.png)" in row  # its own picture, in its own row


def test_the_readme_table_holds_only_built_in_scenes_and_existing_pictures():
    names = {p.name for p in builtin_scenes()}
    assert set(_table_rows()) <= names
    linked = re.findall(r"\]\((docs/images/scenes/[^)]+)\)", _scenes_section())
    assert linked and all((ROOT / link).is_file() for link in linked)
    assert {Path(p).stem for p in linked} == {Path(n).stem for n in names}
    pictures = {p.stem for p in PICTURES.glob("*.png")}
    assert pictures == {Path(n).stem for n in names}  # no picture of a scene that is gone
    assert sum(p.stat().st_size for p in PICTURES.glob("*.png")) < TOTAL_BYTES

