"""The dashboard's mission editor as the browser mission tests drive it
(tests/browser/missions/): the vehicles' states and missions through the API, the
fleet list and panels opened at each screen size, and screenshots saved by name."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import httpx
from playwright.sync_api import Page, expect

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data" / "qgc"
OUTPUT = REPO / "test-output" / "missions"
README_IMAGE = REPO / "docs" / "img" / "dashboard-map.png"
MISSION_VEHICLE = "sim_3"
GOTO_VEHICLE = "sim_1"
CHECK_S = 15  # the editor checks 0.4 s after an edit; the hub answers at once


def shot(page: Page, name: str, size: str) -> None:
    OUTPUT.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=OUTPUT / f"{name}-{size}.png")


def vehicle_states(api: httpx.Client) -> dict[str, dict[str, Any]]:
    return {v["id"]: v["state"] or {} for v in api.get("/api/v1/vehicles").json()}


def small(size: str) -> bool:
    return size != "desktop"


def toggle_drawer(page: Page, size: str, drawer: str, open_: bool) -> None:
    """On a tablet or a phone the fleet list and the panels are drawers beside the map."""
    if not small(size):
        return
    button = page.locator(f'button[data-action="drawer-{drawer}"]')
    if (button.get_attribute("aria-expanded") == "true") != open_:
        button.click()
    expect(button).to_have_attribute("aria-expanded", str(open_).lower())


def select(page: Page, size: str, vehicle: str) -> None:
    toggle_drawer(page, size, "fleet", True)
    page.locator(f'tr[data-vehicle-id="{vehicle}"] td[data-field="mode"]').click()
    toggle_drawer(page, size, "fleet", False)
    expect(page.locator('[data-field="mission-vehicle"]')).to_contain_text(vehicle)


def open_panel(page: Page, size: str, vehicle: str) -> None:
    select(page, size, vehicle)
    expand_panel(page)


def expand_panel(page: Page) -> None:
    toggle = page.locator('[data-action="mission-toggle"]')
    if toggle.get_attribute("aria-expanded") != "true":
        toggle.click()
    expect(page.locator(".mission-body")).to_be_visible()


def collapse_panel(page: Page) -> None:
    toggle = page.locator('[data-action="mission-toggle"]')
    if toggle.get_attribute("aria-expanded") == "true":
        toggle.click()
    expect(page.locator(".mission-body")).to_be_hidden()


def mission_on_board(api: httpx.Client, vehicle: str) -> list[dict[str, Any]]:
    """The vehicle's mission as it reads back from the vehicle, home (item 0) left out."""
    answer = api.get(f"/api/v1/vehicles/{vehicle}/mission")
    assert answer.status_code == 200, answer.text
    items: list[dict[str, Any]] = answer.json()["items"][1:]
    return items
