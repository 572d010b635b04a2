from __future__ import annotations

import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from playwright.sync_api import Browser, Page, sync_playwright

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
# Without these, Chromium keeps trying to reach Google's services on a closed network.
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]

# The screens operators use: a laptop, a 1024x768 tablet, a phone.
SIZES = {"desktop": (1920, 1080), "tablet": (1024, 768), "phone": (390, 844)}


# One Chromium for all of tests/browser (package scope: pytest closes it after the
# package's last test; each test still gets a fresh context, so no cookie or storage
# crosses tests). Not session scope: Playwright's sync API keeps an event loop running
# in this thread while it is open, which would stop the tests after this package from
# using asyncio.run().
@pytest.fixture(scope="package")
def browser() -> Iterator[Browser]:
    # Playwright gives each launch a fresh, empty profile of its own.
    with sync_playwright() as playwright:
        launched = playwright.chromium.launch(
            executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS
        )
        yield launched
        launched.close()


@contextmanager
def checked_page(browser: Browser, width: int, height: int, **options: Any) -> Iterator[Page]:
    """A page in a fresh context of that size (and Playwright's context ``options``); any
    JavaScript error on it fails the test."""
    context = browser.new_context(viewport={"width": width, "height": height}, **options)
    opened = context.new_page()
    errors: list[str] = []
    opened.on("pageerror", lambda error: errors.append(str(error)))
    yield opened
    context.close()
    assert errors == [], f"JavaScript errors on the page: {errors}"


@pytest.fixture
def page(browser: Browser) -> Iterator[Page]:
    with checked_page(browser, 1400, 900) as opened:
        yield opened


@pytest.fixture
def wide_page(browser: Browser) -> Iterator[Page]:
    """Room for a planning panel beside the fleet list and the map."""
    with checked_page(browser, 1600, 1000) as opened:
        yield opened


def log_in(page: Page, base_url: str, username: str, password: str) -> None:
    """Through the dashboard's own login form, as an operator would."""
    page.goto(base_url + "/")
    page.locator('#login input[name="username"]').fill(username)
    page.locator('#login input[name="password"]').fill(password)
    page.locator('#login [type="submit"]').click()
