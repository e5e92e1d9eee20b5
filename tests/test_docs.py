"""The documentation site and the notebook (issue #28).

`make docs` builds the site with mkdocs in strict mode, so a broken link between pages, a
missing anchor or a page left out of the navigation is already an error of the build; this test
runs that build and then checks what mkdocs does not: every local href and src of the built HTML
(pictures, downloads, anchors in other pages) exists, the generated reference pages hold what
the code holds (every command, every scene key the loader accepts), the README stays short and
its links resolve, and the notebook runs as a notebook.
"""

from __future__ import annotations

import html.parser
import os
import re
import subprocess
import sys
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

from conftest import ROOT, process_timeout

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet", "--site-dir", str(out)],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=process_timeout(2.0))
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out


class _Links(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.links: list[str] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if name in ("href", "src") and value:
                self.links.append(value)
            if name == "id" and value:
                self.ids.add(value)


def _parse(path: Path) -> _Links:
    parser = _Links()
    parser.feed(path.read_text(encoding="utf-8"))
    return parser


def test_every_local_link_of_the_built_site_resolves(site):
    pages = {p: _parse(p) for p in site.rglob("*.html")}
    assert len(pages) > 20
    broken = []
    for page, parsed in pages.items():
        for link in parsed.links:
            parts = urlsplit(link)
            if parts.scheme or link.startswith(("//", "mailto:", "data:", "javascript:")):
                continue
            path = unquote(parts.path)
            base = site if path.startswith("/") else page.parent  # the 404 page links from the site's root
            target = (base / path.lstrip("/")).resolve() if path else page
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                broken.append(f"{page.relative_to(site)} -> {link}")
            elif parts.fragment and target.suffix == ".html":
                ids = pages[target].ids if target in pages else _parse(target).ids
                if parts.fragment not in ids:
                    broken.append(f"{page.relative_to(site)} -> {link} (no such anchor)")
    assert not broken, "\n".join(broken)


def test_the_site_loads_nothing_from_the_network(site):
    """Offline: no fonts, scripts or styles from another host (the offline plugin, font: false)."""
    remote = set()
    for page in site.rglob("*.html"):
        for link in _parse(page).links:
            if link.startswith(("http://", "https://", "//")) and re.search(r"\.(js|css|woff2?|ttf)(\?|$)", link):
                remote.add(link)
    assert not remote, remote


def test_the_cli_reference_is_every_command_of_the_parser(site):
    from explorer.cli import COMMAND_MODULES

    text = (site / "reference" / "cli.html").read_text()
    for module in COMMAND_MODULES:
        name = module.rsplit(".", 1)[1]
        assert f"explorer {name}" in text and f"usage: explorer {name}" in text, name


def test_the_scene_key_reference_holds_every_key_the_loader_accepts(site):
    """A key the loader reads (or a table accepts) and the page misses would be a hole in the
    reference; a few that every scene has, with their units and defaults, are checked as written."""
    text = (site / "reference" / "scene-keys.html").read_text()
    for key in ("drive.rpm", "lift.law", "valve.lash", "spring.preload", "linkage.stiffness", "solver.method",
                "gear.trip.buffer", "lift.stations[].angle", "cam.arcs[].radius"):
        assert f"<code>{key}</code>" in text, key
    row = re.search(r"<code>valve\.lash</code></td>\s*<td>(.*?)</td>\s*<td>(.*?)</td>\s*<td>(.*?)</td>", text, re.S)
    assert row and "length [m]" in row.group(1) and row.group(3).strip() == "0 m", row and row.groups()


def test_the_readme_is_short_and_its_links_resolve():
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= 250
    for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", readme):
        if not urlsplit(target).scheme:
            assert (ROOT / target).exists(), target


def test_the_notebook_runs_as_a_notebook(tmp_path):
    """notebooks/tour.py, converted by jupytext and executed cell by cell by nbclient in a
    kernel of this interpreter; its pictures are written and its own assertions hold."""
    jupytext = pytest.importorskip("jupytext")
    nbclient = pytest.importorskip("nbclient")
    notebook = jupytext.read(ROOT / "notebooks" / "tour.py")
    client = nbclient.NotebookClient(notebook, timeout=int(process_timeout()), kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    printed = "".join(out.get("text", "") for cell in notebook.cells for out in cell.get("outputs", []))
    assert "first leaves the cam at" in printed
    assert (tmp_path / "tour_revolution.png").stat().st_size > 10_000
    assert (tmp_path / "tour_sweep.png").stat().st_size > 10_000
