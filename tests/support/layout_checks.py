"""The dashboard's layout measured in the page, at whatever size it is: which shown
elements' boxes reach past the viewport's sides (cut off or scrolled sideways), and which
visible controls another element covers. Each returns descriptions (empty when all is
well), so a test can assert ``== []`` and show what is wrong when it is not. The
measuring runs in the page: layout_checks.js."""

from __future__ import annotations

from pathlib import Path

from playwright.sync_api import Page

_MEASURE_JS = Path(__file__).with_suffix(".js").read_text(encoding="utf-8")


def overflowing_elements(page: Page) -> list[str]:
    """Every shown element whose box reaches past the viewport's left or right edge (the
    map's own panes and tiles excepted, and what is scrolled out of a list), and a page
    that scrolls sideways; empty when none."""
    found: list[str] = page.evaluate(_MEASURE_JS, ["overflowing", None])
    return found


def covered_controls(page: Page, allowed_over: str | None = None) -> list[str]:
    """Every shown control (button, select, input, summary, link) on screen whose centre
    belongs to another element: `document.elementFromPoint` there returns neither it nor
    one of its descendants. Empty when every control can be pressed where it is drawn.
    ``allowed_over`` is a CSS selector of what may lie over controls (a menu opened on
    purpose covers the page under it)."""
    found: list[str] = page.evaluate(_MEASURE_JS, ["covered", allowed_over])
    return found
