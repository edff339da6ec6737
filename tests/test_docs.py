"""The documentation site builds in strict mode, its CLI reference matches the installed commands,
its images are small and every example package is documented."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
MAX_IMAGE_BYTES = 300 * 1024


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site")
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(ROOT / "mkdocs.yml"), "-d", str(out)],
                          cwd=ROOT, capture_output=True, text=True, timeout=300)
    return out, proc


def test_site_builds_in_strict_mode_without_warnings(site):
    out, proc = site
    log = proc.stdout + proc.stderr
    assert proc.returncode == 0, log
    assert "WARNING" not in log, log
    assert (out / "index.html").is_file()


def test_every_nav_page_is_built(site):
    out, proc = site
    assert proc.returncode == 0, proc.stderr
    nav_pages = re.findall(r":\s*([\w./-]+\.md)\s*$", (ROOT / "mkdocs.yml").read_text(encoding="utf-8"), flags=re.M)
    assert "quickstart.md" in nav_pages and "plugins.md" in nav_pages and "cli.md" in nav_pages
    for page in nav_pages:
        html = out / ("index.html" if page == "index.md" else page[:-3] + "/index.html")
        assert html.is_file(), page
        assert len(html.read_text(encoding="utf-8")) > 2000, page


def test_cli_reference_matches_the_installed_commands():
    proc = subprocess.run([sys.executable, str(DOCS / "gen_cli_reference.py"), "--check"], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    text = (DOCS / "cli.md").read_text(encoding="utf-8")
    from infuse.cli import build_parser

    parser = build_parser()
    (commands,) = [a.choices for a in parser._actions if hasattr(a, "choices") and isinstance(a.choices, dict)]
    for name in commands:
        assert f"## `infuse {name}`" in text, name


def test_doc_images_exist_and_are_small():
    referenced = set()
    for page in DOCS.glob("*.md"):
        referenced |= set(re.findall(r"!\[[^\]]*\]\((images/[^)\s]+\.png)\)", page.read_text(encoding="utf-8")))
    assert referenced, "the docs show no image"
    for rel in referenced:
        assert (DOCS / rel).is_file(), rel
    for png in (DOCS / "images").glob("*.png"):
        assert png.stat().st_size < MAX_IMAGE_BYTES, f"{png.name}: {png.stat().st_size} bytes"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", png.name


def test_every_example_package_has_a_guide():
    guide = (DOCS / "plugins.md").read_text(encoding="utf-8")
    examples = [p.parent.name for p in (ROOT / "examples").glob("*/pyproject.toml")]
    assert len(examples) >= 4
    for name in examples:
        assert f"examples/{name}" in guide, name
