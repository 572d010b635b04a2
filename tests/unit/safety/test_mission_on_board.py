"""The AUTO gate against the mission read from the vehicle: a switch to AUTO flies only a
checked mission (an unreadable or empty one is a violation), and a new current item must
be one of the mission's; the vehicle's own item count spares the download when it can."""

from __future__ import annotations

import asyncio

import pytest

from backend.errors import InvalidRequest, VehicleRefused
from backend.safety import PlanCheck, Violation
from backend.safety.mission_on_board import (
    MissionReader,
    check_current_item,
    starts_mission,
    unchecked_mission,
)
from protocol.messages import (
    HoldCommand,
    MissionItem,
    MissionSetCurrentCommand,
    SetModeCommand,
)

WAYPOINT = MissionItem(command=16, lat=47.0, lon=8.0, alt=20)


def reader(items: list[MissionItem], reads: list[int] | None = None) -> MissionReader:
    async def read() -> list[MissionItem]:
        if reads is not None:
            reads.append(1)
        return items

    return read


async def refused() -> list[MissionItem]:
    raise VehicleRefused("mission download: timed out")


def passes(items: list[MissionItem]) -> PlanCheck:
    return PlanCheck((), None)


def test_only_the_mission_modes_start_a_mission() -> None:
    assert starts_mission(SetModeCommand(mode="auto"))
    assert not starts_mission(SetModeCommand(mode="LOITER"))
    assert not starts_mission(HoldCommand())


def test_the_mission_on_board_is_checked_and_counted() -> None:
    found = Violation("geofence", "waypoint 1 is 50 m outside the geofence")
    checked = asyncio.run(
        unchecked_mission(reader([WAYPOINT] * 3), lambda items: PlanCheck((found,), None))
    )
    assert checked == ([found], 3)
    assert asyncio.run(unchecked_mission(reader([WAYPOINT]), passes)) == ([], 1)


def test_an_unreadable_or_empty_mission_is_unchecked() -> None:
    [unreadable], count = asyncio.run(unchecked_mission(refused, passes))
    assert (unreadable.rule, count) == ("mission_unchecked", 0)
    assert "could not be read" in unreadable.message
    [empty], count = asyncio.run(unchecked_mission(reader([]), passes))
    assert (empty.rule, count) == ("mission_unchecked", 0)
    assert "no mission to fly" in empty.message


def test_a_current_item_within_the_vehicles_count_needs_no_download() -> None:
    reads: list[int] = []
    asyncio.run(check_current_item(reader([], reads), 5, MissionSetCurrentCommand(seq=5)))
    asyncio.run(check_current_item(reader([], reads), None, HoldCommand()))
    assert reads == []


def test_a_current_item_beyond_the_mission_on_board_is_refused_naming_its_length() -> None:
    reads: list[int] = []
    two = reader([WAYPOINT, WAYPOINT], reads)
    asyncio.run(check_current_item(two, 1, MissionSetCurrentCommand(seq=2)))  # a fresh upload
    with pytest.raises(InvalidRequest, match=r"item 3 is not in the mission: it has 2 items"):
        asyncio.run(check_current_item(two, None, MissionSetCurrentCommand(seq=3)))
    with pytest.raises(InvalidRequest, match="it holds no mission"):
        asyncio.run(check_current_item(reader([]), 0, MissionSetCurrentCommand(seq=1)))
    assert reads == [1, 1]
