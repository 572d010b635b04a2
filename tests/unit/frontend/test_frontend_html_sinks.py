"""The dashboard never hands a string to anything that parses it as HTML.

Texts from vehicles (STATUSTEXT events, mode names) and users (names, reasons) reach
the page; each must be set as text (`textContent`, an element for Leaflet). Leaflet's
tooltips, popups and divIcons take a string as HTML, as `innerHTML` does, so any of
these given a string literal or template is refused here, in every source file.
"""

from __future__ import annotations

import re
from pathlib import Path

SOURCES = Path(__file__).resolve().parents[3] / "frontend" / "src"
HTML_SINKS = re.compile(
    r"\.(innerHTML|outerHTML)\s*\+?=(?!=)"
    r"|\binsertAdjacentHTML\s*\("
    r"|\bdocument\.write(ln)?\s*\("
    r"|\bcreateContextualFragment\s*\("
    r"|\bsetHTMLUnsafe\s*\("
    r"|\b(bindTooltip|bindPopup|setContent|setTooltipContent|setPopupContent)\s*\(\s*[`'\"]"
    r"|\bhtml\s*:\s*[`'\"]"
)


def test_no_source_passes_a_string_to_an_html_sink() -> None:
    files = sorted(SOURCES.rglob("*.ts"))
    assert files, f"no TypeScript under {SOURCES}"
    found = [
        f"{path.relative_to(SOURCES)}:{number}: {line.strip()}"
        for path in files
        for number, line in enumerate(path.read_text().splitlines(), start=1)
        if HTML_SINKS.search(line)
    ]
    assert found == [], "strings parsed as HTML:\n" + "\n".join(found)
