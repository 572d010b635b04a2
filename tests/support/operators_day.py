"""The operator's day (tests/browser/test_operators_day.py): the day's page, its
screenshots and layout measurements, and the dashboard's parts as an operator finds them.

Every selector the day uses is here, one small function each, so that a change of the
dashboard's layout is one edit."""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
from playwright.sync_api import FloatRect, Locator, Page, expect

from common.geodesy import LocalFrame
from tests.support.layout_checks import covered_controls, overflowing_elements
from tests.support.maps import PixelMap, _assert_on_open_map, _box
from tests.support.waiting import poll_until

SHOTS_VARIABLE = "GCS_DAY_SHOTS"
States = dict[str, dict[str, Any]]  # each vehicle's latest state, by its id


@dataclass
class Day:
    """One size's day: the page, a read-only API client to wait on, where its shots go,
    and the layout faults each step measured."""

    page: Page
    size: str
    api: httpx.Client
    shots: Path
    frame: LocalFrame  # metres about the first vehicle's home
    faults: dict[str, list[str]] = field(default_factory=dict)
    steps: int = 0

    @property
    def small(self) -> bool:
        return self.size != "desktop"

    def shot(self, step: str) -> None:
        """The screenshot of a step, and its layout measured."""
        self.steps += 1
        name = f"{self.size}-{self.steps:02d}-{step}"
        self.page.screenshot(path=self.shots / f"{name}.png")
        found = [f"overflows: {o}" for o in overflowing_elements(self.page)]
        found += [f"covered: {c}" for c in covered_controls(self.page)]
        if found:
            self.faults[name] = found

    def states(self) -> States:
        return {v["id"]: v["state"] or {} for v in self.api.get("/api/v1/vehicles").json()}

    def wait(self, test: Callable[[States], object], s: float, what: str) -> None:
        """API reads only: to wait for the fleet's state, never to act on it."""
        poll_until(lambda: test(self.states()), s, what)


def patient_token(base_url: str, password: str) -> str:
    """The admin's bearer token, waiting out a hub busy starting four drones' feeds."""
    response = httpx.post(
        f"{base_url}/api/v1/auth/token",
        data={"username": "admin", "password": password},
        timeout=60,
    )
    response.raise_for_status()
    token: str = response.json()["access_token"]
    return token


def metres_forward(start: dict[str, Any], now: dict[str, Any]) -> float:
    """How far a vehicle moved along the heading it had at ``start`` (metres; negative:
    backwards): what pitching forward flies, whichever way it faces."""
    north = (now["lat"] - start["lat"]) * 111_320
    east = (now["lon"] - start["lon"]) * 111_320 * math.cos(math.radians(start["lat"]))
    heading = math.radians(start["heading_deg"])
    return north * math.cos(heading) + east * math.sin(heading)


def shots_folder(default: Path) -> Path:
    folder = Path(os.environ.get(SHOTS_VARIABLE) or default)
    folder.mkdir(parents=True, exist_ok=True)
    return folder


# -- the dashboard's parts ------------------------------------------------------------


def drawer(day: Day, name: str, open_: bool) -> None:
    """On a tablet or a phone the fleet ("fleet", "Vehicles") and the panels ("ops",
    "Panels") are drawers beside or under the map; a desktop shows both in its side column."""
    if not day.small:
        return
    button = day.page.locator(f'button[data-action="drawer-{name}"]')
    if (button.get_attribute("aria-expanded") == "true") != open_:
        button.click()
    expect(button).to_have_attribute("aria-expanded", str(open_).lower())


def fleet_entry(page: Page, vehicle: str) -> Locator:
    """A vehicle's card in the fleet (a table row drawn as a card)."""
    return page.locator(f'tr[data-vehicle-id="{vehicle}"]')


def select_vehicle(day: Day, vehicle: str) -> None:
    drawer(day, "fleet", True)
    fleet_entry(day.page, vehicle).locator('[data-field="mode"]').click()
    drawer(day, "fleet", False)
    expect(day.page.locator('[data-field="mission-vehicle"]')).to_contain_text(vehicle)


def take_off(day: Day, vehicle: str, altitude: float) -> None:
    """The fleet's Takeoff button (it arms in GUIDED and climbs)."""
    drawer(day, "fleet", True)
    entry = fleet_entry(day.page, vehicle)
    entry.locator('input[data-field="takeoff-altitude"]').fill(f"{altitude:g}")
    entry.locator('button[data-action="takeoff"]').click()
    # Its answer shows on the row; whether it came in time is the caller's wait on the
    # climb (on a loaded machine the hub's 15 s for the agent's answer can run out while
    # the vehicle takes off).
    expect(entry.locator('[data-field="command-result"]')).to_contain_text("takeoff")
    drawer(day, "fleet", False)


def mission_panel(page: Page) -> Locator:
    return page.locator(".mission-panel")


def panel_open(page: Page, toggle: str, body: str, open_: bool) -> None:
    """A panel folded or unfolded by its header's toggle."""
    button = page.locator(f'[data-action="{toggle}"]')
    if (button.get_attribute("aria-expanded") == "true") != open_:
        button.click()
    if open_:
        expect(page.locator(body)).to_be_visible()
    else:
        expect(page.locator(body)).to_be_hidden()


def mission_open(page: Page, open_: bool) -> None:
    panel_open(page, "mission-toggle", ".mission-body", open_)


def survey_open(page: Page, open_: bool) -> None:
    panel_open(page, "survey-toggle", ".survey-body", open_)


def formation_open(page: Page) -> Locator:
    page.locator('[data-action="formation-toggle"]').click()
    return page.locator(".formation-panel")


def pilot_panel(day: Day) -> Locator:
    """The pilot panel (its fields' names kept by the restyle), in the panels' drawer."""
    drawer(day, "ops", True)
    return day.page.locator('[data-panel="pilot"]')


def flights_button(page: Page) -> Locator:
    """The Flights button; on a phone it is in the header's menu, opened first."""
    menu = page.locator('button[data-action="header-menu"]')
    if menu.is_visible() and menu.get_attribute("aria-expanded") != "true":
        menu.click()
    return page.get_by_role("button", name="Flights")


def view_3d_button(page: Page) -> Locator:
    return page.locator(".viz3d-toggle")


# -- the map --------------------------------------------------------------------------


def open_space(day: Day, panel: str) -> FloatRect:
    """The map not under ``panel``, below the controls along its top: beside the panel
    when it leaves room, else the whole map (a phone: the panel is folded to draw)."""
    area = _box(day.page, "#map")
    top, bottom = area["y"] + 70, area["y"] + area["height"] - 40
    shown = day.page.locator(panel).first
    box = shown.bounding_box() if shown.is_visible() else None
    width = area["width"]
    if box is not None and box["x"] - area["x"] >= 300:
        width = box["x"] - area["x"] - 20
    return {"x": area["x"], "y": top, "width": width, "height": bottom - top}


def frame_on_map(
    day: Day, centre_m: tuple[float, float], size_m: tuple[float, float], space: FloatRect
) -> PixelMap:
    """Zoom until a ``size_m`` box fills a good part of ``space``, then drag the map to put
    ``centre_m`` (east, north) in its middle."""
    page = day.page
    pixels = PixelMap(page, settle_s=30)
    for _ in range(8):
        wide, deep = (m / pixels.metres_per_px() for m in size_m)
        if wide > space["width"] * 0.8 or deep > space["height"] * 0.7:
            page.locator(".leaflet-control-zoom-out").click()
        elif wide < space["width"] * 0.3 and deep < space["height"] * 0.3:
            page.locator(".leaflet-control-zoom-in").click()
        else:
            break
        pixels = PixelMap(page, settle_s=30)
    centre = pixels.pixel(*day.frame.to_geo(*centre_m))
    wanted = (space["x"] + space["width"] / 2, space["y"] + space["height"] / 2)
    start = pixels.a
    page.mouse.move(*start)
    page.mouse.down()
    page.mouse.move(start[0] + wanted[0] - centre[0], start[1] + wanted[1] - centre[1], steps=15)
    page.mouse.up()
    return PixelMap(page, settle_s=30)


def map_point(day: Day, pixels: PixelMap, east: float, north: float) -> tuple[float, float]:
    """Where (east, north) is drawn, checked to be open map a click reaches."""
    x, y = pixels.pixel(*day.frame.to_geo(east, north))
    _assert_on_open_map(day.page, x, y)
    return x, y


def drag(page: Page, target: Locator, dx: float, dy: float) -> Callable[[], None]:
    """Press in the middle of ``target`` and move by (dx, dy); returns the release."""
    target.scroll_into_view_if_needed()
    box = target.bounding_box()
    assert box is not None
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x + dx, y + dy, steps=8)
    return page.mouse.up
