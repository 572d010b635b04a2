"""The mission check's minimum height above home (a default rail) and its take-offs, judged
by what each autopilot does with them: a navigation item below home is refused in every
global frame, a landing is not held to it; PX4 flies to a take-off's position, so there
a take-off is a place the rails check, and 0, 0 is refused naming the item."""

from __future__ import annotations

import dataclasses

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from backend.safety import SafetyRails, VehicleSnapshot, check_mission
from backend.safety.rails import DEFAULT_MIN_HEIGHT_ABOVE_HOME_M
from backend.safety.schemas import SafetyRailsModel
from backend.settings import HubSettings
from backend.survey.planning.schemas import SurveyRequest
from backend.survey.planning.survey import Fleet, plan_survey
from protocol.messages import MissionItem
from tests.unit.safety.shapes import geo, north_of, vehicle

WAYPOINT = mavlink2.MAV_CMD_NAV_WAYPOINT
TAKEOFF = mavlink2.MAV_CMD_NAV_TAKEOFF
LAND = mavlink2.MAV_CMD_NAV_LAND
RTL = mavlink2.MAV_CMD_NAV_RETURN_TO_LAUNCH
HOME_MSL = 584.0
RULE = "(min_height_above_home_m)"
NEED = f"the rails need at least 2.0 m above home {RULE}"


def _vehicle(**changes: object) -> VehicleSnapshot:
    return dataclasses.replace(vehicle(), home_alt_msl=HOME_MSL, **changes)  # type: ignore[arg-type]


def _near(alt: float, frame: int, command: int = WAYPOINT) -> MissionItem:
    p = north_of(geo(50, 50), 30)
    return MissionItem(command=command, frame=frame, lat=p.lat, lon=p.lon, alt=alt)


def _check(
    items: list[MissionItem],
    rails: SafetyRails | None = None,
    vehicle_type: str = "multirotor",
    autopilot: str = "ardupilot",
    snapshot: VehicleSnapshot | None = None,
) -> list[tuple[str, str, tuple[int, ...]]]:
    limits = rails if rails is not None else SafetyRails()
    checked = check_mission(items, snapshot or _vehicle(), lambda: limits, vehicle_type, autopilot)
    return [(v.rule, v.message, v.items) for v in checked.violations]


def _heights(
    violations: list[tuple[str, str, tuple[int, ...]]],
) -> list[tuple[str, tuple[int, ...]]]:
    return [
        (message, items) for rule, message, items in violations if rule == "min_height_above_home"
    ]


def test_the_default_rails_keep_two_metres_above_home() -> None:
    assert SafetyRails().min_height_above_home_m == DEFAULT_MIN_HEIGHT_ABOVE_HOME_M == 2.0
    assert SafetyRailsModel().min_height_above_home_m == 2.0
    assert HubSettings().min_height_above_home_m == 2.0
    # a stored body from before the rail (no such field) gets it, not nothing
    assert SafetyRailsModel.model_validate_json("{}").to_rails().min_height_above_home_m == 2.0


@pytest.mark.parametrize(
    ("frame", "alt", "message"),
    [
        (3, -50.0, f"item 2: 50.0 m below home (-50.0 m); {NEED}"),
        (6, -50.0, f"item 2: 50.0 m below home (-50.0 m); {NEED}"),
        (3, 1.0, f"item 2: 1.0 m above home; {NEED}"),
        (
            0,
            0.0,
            f"item 2: 584.0 m below home (0.0 m above sea level; home is at 584.0 m); {NEED}",
        ),
        (
            5,
            0.0,
            f"item 2: 584.0 m below home (0.0 m above sea level; home is at 584.0 m); {NEED}",
        ),
        (
            10,
            1.5,
            "item 2: 1.5 m above terrain, taken as 1.5 m above home (the hub has no terrain "
            f"model); {NEED}",
        ),
        (
            11,
            -3.0,
            "item 2: -3.0 m above terrain, taken as 3.0 m below home (the hub has no terrain "
            f"model); {NEED}",
        ),
    ],
)
def test_a_waypoint_below_the_minimum_is_refused_in_every_global_frame(
    frame: int, alt: float, message: str
) -> None:
    items = [_near(10, 3, TAKEOFF), _near(alt, frame), MissionItem(command=RTL)]
    assert _heights(_check(items)) == [(message, (2,))]


@pytest.mark.parametrize(
    ("frame", "alt"), [(3, 2.0), (6, 40.0), (0, 586.0), (5, 624.0), (10, 2.0), (11, 30.0)]
)
def test_a_waypoint_at_or_above_the_minimum_passes(frame: int, alt: float) -> None:
    items = [_near(10, 3, TAKEOFF), _near(alt, frame), MissionItem(command=RTL)]
    assert _check(items) == []


def test_the_lowest_is_named_and_every_low_item_listed() -> None:
    items = [_near(10, 3, TAKEOFF), _near(1, 3), _near(-5, 3), _near(20, 3), _near(0, 3)]
    [(message, at_fault)] = _heights(_check(items))
    assert message == f"item 3: 5.0 m below home (-5.0 m); {NEED} (3 waypoints are below it)"
    assert at_fault == (2, 3, 5)


def test_a_landing_is_not_held_above_home() -> None:
    # down to the ground, in its frame: a land below home (a lower field) is a landing too
    for frame, alt in ((3, 0.0), (0, HOME_MSL - 10), (10, 0.0)):
        items = [_near(10, 3, TAKEOFF), _near(20, 3), _near(alt, frame, LAND)]
        assert _heights(_check(items)) == [], (frame, alt)
    # ...but a loiter down there is not a landing
    items = [_near(10, 3, TAKEOFF), _near(0, 3, mavlink2.MAV_CMD_NAV_LOITER_TIME)]
    assert len(_heights(_check(items))) == 1


def test_a_low_take_off_is_refused_too() -> None:
    assert _heights(_check([_near(1, 3, TAKEOFF)])) == [(f"item 1: 1.0 m above home; {NEED}", (1,))]


def test_the_rule_follows_the_rails() -> None:
    low = [_near(10, 3, TAKEOFF), _near(3, 3)]
    assert _heights(_check(low, SafetyRails(min_height_above_home_m=5.0))) == [
        (f"item 2: 3.0 m above home; the rails need at least 5.0 m above home {RULE}", (2,))
    ]
    # a site may switch it off; a vehicle's own rails cannot, nor fall back to the default
    off = SafetyRails(min_height_above_home_m=None)
    assert _check([_near(10, 3, TAKEOFF), _near(-50, 3)], off) == []
    assert off.merged_with(SafetyRails()).min_height_above_home_m is None
    assert SafetyRails().merged_with(off).min_height_above_home_m == 2.0
    site = SafetyRails(min_height_above_home_m=10.0)
    assert site.merged_with(SafetyRails()).min_height_above_home_m == 10.0
    assert (
        site.merged_with(SafetyRails(min_height_above_home_m=15.0)).min_height_above_home_m == 15.0
    )


def test_a_rover_s_altitude_is_not_a_height_to_keep() -> None:
    items = [_near(0, 3), _near(-1, 3)]
    assert _check(items, vehicle_type="rover") == []
    assert _check(items, vehicle_type="boat") == []


# -- take-offs, as each autopilot flies them ----------------------------------------------


def _takeoff_at(lat: float, lon: float) -> list[MissionItem]:
    here = geo(50, 50)
    return [
        MissionItem(command=TAKEOFF, frame=3, lat=lat, lon=lon, alt=40),
        MissionItem(command=WAYPOINT, frame=3, lat=here.lat + 1e-4, lon=here.lon, alt=40),
        MissionItem(command=RTL),
    ]


def test_px4_flies_to_a_take_off_s_position_so_zero_zero_is_refused_naming_it() -> None:
    rails = SafetyRails(max_distance_from_home_m=2000)
    violations = _check(_takeoff_at(0.0, 0.0), rails, autopilot="px4")
    rules = {rule: (message, items) for rule, message, items in violations}
    assert rules["mission_item"] == (
        "item 1 (NAV_TAKEOFF): latitude and longitude are 0, 0: PX4 flies to a take-off's "
        "position once it has climbed (give where the vehicle takes off)",
        (1,),
    )
    message, items = rules["max_distance_from_home"]
    assert message.startswith("item 1 is ")
    assert items == (1,)


def test_px4_s_take_off_far_from_home_is_checked_as_a_place() -> None:
    far = north_of(geo(50, 50), 800)
    rails = SafetyRails(max_distance_from_home_m=500)
    violations = _check(_takeoff_at(far.lat, far.lon), rails, autopilot="px4")
    assert [(rule, items) for rule, _, items in violations] == [("max_distance_from_home", (1,))]
    assert violations[0][1].startswith("item 1 is 800 m from home")
    # ArduPilot's copters climb where they stand: the same item is harmless there
    assert _check(_takeoff_at(far.lat, far.lon), rails, autopilot="ardupilot") == []


def test_a_take_off_where_the_vehicle_stands_passes_on_both() -> None:
    here = geo(50, 50)
    rails = SafetyRails(max_distance_from_home_m=2000)
    for autopilot in ("px4", "ardupilot"):
        assert _check(_takeoff_at(here.lat, here.lon), rails, autopilot=autopilot) == []
    # ArduPilot ignores a take-off's position: 0, 0 there is no place (as QGC writes it)
    assert _check(_takeoff_at(0.0, 0.0), rails, autopilot="ardupilot") == []


def test_a_survey_takes_off_where_the_drone_stands_and_passes_on_px4_and_ardupilot() -> None:
    here = geo(50, 50)
    ring = [geo(e, n) for e, n in ((80, 80), (280, 80), (280, 230), (80, 230), (80, 80))]
    request = SurveyRequest.model_validate(
        {
            "area": {"type": "Polygon", "coordinates": [[[p.lon, p.lat] for p in ring]]},
            "camera": "sony_a6000_16mm",
            "altitude_m": 40,
            "angle_deg": 0,
            "vehicle_ids": ["d1"],
        }
    )
    [part] = plan_survey(request, [Fleet("d1", here, here)]).parts
    takeoff = part.items[0]
    assert takeoff.command == TAKEOFF
    assert (takeoff.lat, takeoff.lon) == (here.lat, here.lon)
    assert all((i.lat, i.lon) != (0.0, 0.0) for i in part.items if i.command in (TAKEOFF, WAYPOINT))
    rails = SafetyRails(max_distance_from_home_m=2000)
    for autopilot in ("px4", "ardupilot"):
        assert _check(part.items, rails, autopilot=autopilot) == [], autopilot
