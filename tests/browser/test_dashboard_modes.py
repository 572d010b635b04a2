"""The dashboard keeps a vehicle's modes, which the live feed sends once per connection."""

from __future__ import annotations

import json
import re

import pytest
from playwright.sync_api import Page, expect

from gcs.launcher import LocalFleet
from protocol.messages import CLIENT_WS_PATH
from tests.browser.conftest import log_in

pytestmark = [pytest.mark.browser, pytest.mark.integration]

VEHICLE = "sim_1"
UPDATES_WITHOUT_MODES = 20


def test_rows_keep_the_modes_through_updates_that_leave_them_out(
    page: Page, fleet: LocalFleet
) -> None:
    updates_without_modes = 0

    def enough_updates(frame: str | bytes) -> bool:
        nonlocal updates_without_modes
        message = json.loads(frame)
        if message["type"] == "vehicles":
            for vehicle in message["vehicles"]:
                if vehicle["id"] == VEHICLE:
                    updates_without_modes += "modes" not in vehicle
        return updates_without_modes >= UPDATES_WITHOUT_MODES

    with page.expect_websocket(lambda socket: socket.url.endswith(CLIENT_WS_PATH)) as opened:
        log_in(page, fleet.plan.hub_http, "admin", fleet.plan.admin_password)
    opened.value.wait_for_event("framereceived", predicate=enough_updates, timeout=30_000)

    row = page.locator(f'tr[data-vehicle-id="{VEHICLE}"]')
    # The modes set_mode takes (ArduCopter's), from the snapshot, still known.
    expect(row.locator('[data-field="mode"]')).to_have_attribute(
        "title", re.compile(r"; modes: .*\bGUIDED\b.*\bLAND\b")
    )
    expect(row.locator('[data-field="id"]')).to_have_attribute(
        "title", f"{VEHICLE}: ardupilot multirotor"
    )
