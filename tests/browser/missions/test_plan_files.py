"""QGroundControl .plan files in the dashboard's mission editor, in headless Chromium
against the package's fleet (conftest.py): a plan opened and saved in QGC's format, sent
to the vehicle it was edited for, and a QGC null never turned into a zero."""

from __future__ import annotations

import json
import re
from pathlib import Path

import httpx
import jsonschema_rs
import pytest
from playwright.sync_api import Page, expect

from common.geodesy import LocalFrame
from gcs.launcher import LocalFleet
from tests.browser.conftest import log_in
from tests.support.maps import (
    PixelMap,
    _assert_on_open_map,
)
from tests.support.mission_editor import (
    CHECK_S,
    DATA,
    MISSION_VEHICLE,
    mission_on_board,
    open_panel,
    select,
    shot,
    vehicle_states,
)

pytestmark = [pytest.mark.browser, pytest.mark.integration]


def test_a_qgc_plan_opens_and_a_saved_plan_is_qgcs_format(
    wide_page: Page, mission_fleet: LocalFleet
) -> None:
    page = wide_page
    log_in(page, mission_fleet.plan.hub_http, "admin", mission_fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    open_panel(page, "desktop", MISSION_VEHICLE)

    source = json.loads((DATA / "simple_square.plan").read_text())
    page.locator('[data-field="mission-file"]').set_input_files(DATA / "simple_square.plan")
    rows = page.locator(".mission-row")
    expect(rows).to_have_count(5)
    expect(rows.nth(0)).to_have_attribute("data-command", "22")
    expect(rows.nth(0).locator('[data-field="frame"]')).to_have_text("m above home")
    expect(page.locator(".mission-item")).to_have_count(5)  # the take-off and four waypoints

    with page.expect_download() as download_info:
        page.locator('[data-action="mission-save"]').click()
    saved = json.loads(Path(download_info.value.path()).read_text())
    schema = json.loads((DATA / "plan.schema.json").read_text())
    errors = [e.message for e in jsonschema_rs.validator_for(schema).iter_errors(saved)]
    assert errors == []
    # The same MAVLink items, NaN (null, "unset": QGC's yaws) kept as null.
    for mine, theirs in zip(saved["mission"]["items"], source["mission"]["items"], strict=True):
        assert (mine["command"], mine["frame"], mine["autoContinue"]) == (
            theirs["command"],
            theirs["frame"],
            theirs["autoContinue"],
        )
        assert [p is None for p in mine["params"]] == [p is None for p in theirs["params"]]
        assert [p for p in mine["params"] if p is not None] == pytest.approx(
            [p for p in theirs["params"] if p is not None]
        )

    # Uploaded to a group (another vehicle ticked on purpose): each vehicle is checked and
    # answers for itself, the plan's own vehicle first.
    page.locator('[data-field="mission-targets"] input[value="sim_2"]').check()
    page.locator('[data-action="mission-upload"]').click()
    status = page.locator('[data-field="mission-status"]')
    expect(status).to_contain_text(re.compile(r"^sim_3: .+\nsim_2: .+$"), timeout=30_000)

    # A file that is not a plan is refused with the field named, and the plan stays.
    # Handed over as bytes: a file on disk removed right after set_input_files could be
    # gone before the page reads it (NotFoundError under load).
    bad = b'{"fileType": "Plan", "version": 1, "mission": {"version": 2, "items": 3}}'
    page.locator('[data-field="mission-file"]').set_input_files(
        {"name": "not-a-plan.json", "mimeType": "application/json", "buffer": bad}
    )
    expect(page.locator('[data-field="mission-status"]')).to_contain_text("mission.items")
    expect(rows).to_have_count(5)


def test_a_plan_goes_to_the_vehicle_it_was_edited_for(
    wide_page: Page, mission_fleet: LocalFleet, api: httpx.Client
) -> None:
    """Select sim_1, then sim_2, edit and upload: the plan is sim_2's and only sim_2 gets
    it (the upload list once kept the first vehicle selected on the page). Another
    vehicle ticked on purpose is checked against its own rails first and, refused, is
    not uploaded, with the reason."""
    page, first, edited, other = wide_page, "sim_1", "sim_2", "sim_3"
    first_before, other_before = mission_on_board(api, first), mission_on_board(api, other)
    log_in(page, mission_fleet.plan.hub_http, "admin", mission_fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    open_panel(page, "desktop", first)
    select(page, "desktop", edited)  # the map pans to it
    page.locator('[data-action="mission-edit"]').click()
    expect(page.locator('[data-field="mission-vehicle"]')).to_have_text(
        f"Editing a plan for {edited}"
    )
    page.locator('[data-action="mission-clear"]').click()
    page.locator('[data-action="mission-add-22"]').click()
    here = vehicle_states(api)[edited]
    frame = LocalFrame(here["lat"], here["lon"], 0.0)
    pixels = PixelMap(page)
    for east, north in ((-8, 25), (8, 25), (8, -25), (-8, -25)):
        x, y = pixels.pixel(*frame.to_geo(east, north))
        _assert_on_open_map(page, x, y)
        page.mouse.click(x, y)
    page.locator('[data-action="mission-add-20"]').click()
    expect(page.locator(".mission-row")).to_have_count(6)

    page.locator('[data-action="mission-upload"]').click()
    status = page.locator('[data-field="mission-status"]')
    expect(status).to_have_text(f"{edited}: uploaded (6 items)", timeout=30_000)
    on_board = mission_on_board(api, edited)
    assert [item["command"] for item in on_board] == [22, 16, 16, 16, 16, 20]
    # A drawn take-off and waypoints leave the yaw unset (keep the heading), as QGC does.
    assert [item["param4"] for item in on_board[:5]] == [None] * 5
    # The take-off stands where the vehicle launches (home), as QGC writes it: PX4 flies
    # to a take-off's position, and at 0, 0 it flew towards 0°N 0°E.
    takeoff = on_board[0]
    home = (here["home_lat"], here["home_lon"])
    assert (takeoff["lat"], takeoff["lon"]) == pytest.approx(home, abs=1e-7)
    assert mission_on_board(api, first) == first_before  # nothing went to the first vehicle

    # The list says where an upload goes: the edited vehicle, ticked; the others not.
    targets = page.locator('[data-field="mission-targets"]')
    expect(targets.locator("input:checked")).to_have_count(1)
    expect(targets.locator(f'input[value="{edited}"]')).to_be_checked()
    expect(targets.locator(".mission-target.edited")).to_have_text(f"{edited} (this plan's)")
    shot(page, "mission-targets", "desktop")

    # Another vehicle ticked on purpose is checked against its own rails: with a 10 m
    # ceiling of its own it refuses the 20 m plan, and is not sent it.
    rails = f"/api/v1/vehicles/{other}/safety-rails"
    assert api.put(rails, json={"max_altitude_m": 10}).status_code == 200
    try:
        page.locator('[data-action="mission-edit"]').click()
        targets.locator(f'input[value="{other}"]').check()
        page.locator('[data-action="mission-upload"]').click()
        expect(status).to_contain_text(
            re.compile(
                rf"^{edited}: uploaded \(6 items\)\n{other}: not uploaded — refused by its "
                r"rails: max_altitude: .+$"
            ),
            timeout=30_000,
        )
        assert mission_on_board(api, other) == other_before
    finally:
        assert api.delete(rails).status_code in (200, 204)


def test_a_qgc_null_stays_unset_or_is_refused_never_zero(
    wide_page: Page, mission_fleet: LocalFleet, api: httpx.Client
) -> None:
    """QGroundControl writes null for what it leaves unset. A null yaw (param4) stays
    unset: sent as MAVLink's NaN ("keep the heading"), read back as null, not 0 (north on
    PX4). A null altitude has no "unset" on the wire: the file is refused naming the item
    and the field (it used to become 0 m above sea level), and the plan open stays."""
    page, vehicle = wide_page, "sim_2"
    log_in(page, mission_fleet.plan.hub_http, "admin", mission_fleet.plan.admin_password)
    expect(page.locator(".vehicle-marker")).to_have_count(3, timeout=30_000)
    open_panel(page, "desktop", vehicle)
    status = page.locator('[data-field="mission-status"]')
    rows = page.locator(".mission-row")

    page.locator('[data-field="mission-file"]').set_input_files(DATA / "unset_yaw.plan")
    expect(status).to_have_text("unset_yaw.plan: 5 items opened.")
    expect(rows).to_have_count(5)
    expect(page.locator('[data-field="mission-verdict"]')).to_contain_text(
        "Rails: OK", timeout=CHECK_S * 1000
    )
    page.locator('[data-action="mission-upload"]').click()
    expect(status).to_have_text(f"{vehicle}: uploaded (5 items)", timeout=30_000)
    on_board = mission_on_board(api, vehicle)
    assert [item["command"] for item in on_board] == [22, 16, 16, 16, 20]
    assert [item["param4"] for item in on_board[:4]] == [None] * 4
    assert on_board[2]["alt"] == 20

    page.locator('[data-action="mission-edit"]').click()
    page.locator('[data-field="mission-file"]').set_input_files(DATA / "null_altitude.plan")
    expect(status).to_have_text(
        "null_altitude.plan could not be opened: item 3: altitude is empty (null) in the "
        ".plan (mission.items[2].params[6])"
    )
    expect(rows).to_have_count(5)
    expect(rows.nth(2).locator('[data-field="alt"]')).to_have_value("20")
    assert mission_on_board(api, vehicle) == on_board
