"""The README is a front door: short, and a way into every guide in docs/; and no link in
the README or the guides leads nowhere (a section moved between pages keeps its links)."""

from __future__ import annotations

import re
from pathlib import Path

from tests.support.docs import README, REPO, pages

MAX_README_LINES = 350
LINK = re.compile(r"\]\(([^)\s]+)\)")


def _anchors(page: Path) -> set[str]:
    """The anchors GitHub gives a page: one per heading outside code, plus `<a id>`s."""
    found: set[str] = set(re.findall(r'<a id="([^"]+)"', page.read_text()))
    in_code = False
    for line in page.read_text().splitlines():
        if line.startswith("```"):
            in_code = not in_code
        elif not in_code and (heading := re.match(r"#+ (.*)", line)):
            text = re.sub(r"[^\w\- ]", "", re.sub(r"[`*]", "", heading[1].strip().lower()))
            found.add(text.replace(" ", "-"))
    return found


def test_the_readme_is_short_and_links_every_guide() -> None:
    text = README.read_text()
    assert len(text.splitlines()) < MAX_README_LINES
    unlinked = [page.name for page in pages()[1:] if f"](docs/{page.name}" not in text]
    assert not unlinked, f"the README links no way into {unlinked}"


def test_every_link_between_the_pages_leads_somewhere() -> None:
    broken: list[str] = []
    for page in [*pages(), REPO / "tests" / "README.md"]:
        for target in LINK.findall(page.read_text()):
            if target.startswith(("http://", "https://", "mailto:")):
                continue
            path, _, anchor = target.partition("#")
            resolved = (page.parent / path).resolve() if path else page
            if not resolved.exists():
                broken.append(f"{page.name}: {target} (no such file)")
            elif anchor and resolved.suffix == ".md" and anchor not in _anchors(resolved):
                broken.append(f"{page.name}: {target} (no such section)")
    assert not broken, broken
