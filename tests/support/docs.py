"""The project's documentation as the tests read it: the README (a front door) and the
guides in docs/. A section can move from one page to another; tests that check what a
section says find the page that holds it here rather than naming a file."""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
README = REPO / "README.md"


def pages() -> list[Path]:
    """The README and every guide in docs/, in a fixed order."""
    return [README, *sorted((REPO / "docs").glob("*.md"))]


def page_holding(text: str) -> Path:
    """The one page that holds `text` (whitespace compared loosely); a heading is given
    with its hashes (``"### Slow tests"``) and found only as a whole line."""
    if text.startswith("#"):
        pattern = re.compile(rf"^{re.escape(text)}[ \t]*$", re.MULTILINE)
        found = [page for page in pages() if pattern.search(page.read_text())]
    else:
        wanted = " ".join(text.split())
        found = [page for page in pages() if wanted in " ".join(page.read_text().split())]
    assert found, f"no page of the README or docs/ holds {text!r}"
    assert len(found) == 1, f"{text!r} is on several pages: {[str(p) for p in found]}"
    return found[0]
