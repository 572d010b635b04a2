"""The position-source prioritiser: best fix, then satellites, and stale receivers left out."""

from __future__ import annotations

import itertools
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.telemetry.positioning import (
    PositionFix,
    PositionTimeouts,
    best,
    candidates,
    choose,
)
from vehicle_agents.telemetry.snapshot import snapshot

NO_GPS = mavlink2.GPS_FIX_TYPE_NO_GPS
NO_FIX = mavlink2.GPS_FIX_TYPE_NO_FIX
FIX_2D = mavlink2.GPS_FIX_TYPE_2D_FIX
FIX_3D = mavlink2.GPS_FIX_TYPE_3D_FIX
DGPS = mavlink2.GPS_FIX_TYPE_DGPS
RTK_FLOAT = mavlink2.GPS_FIX_TYPE_RTK_FLOAT
RTK_FIXED = mavlink2.GPS_FIX_TYPE_RTK_FIXED
STATIC = mavlink2.GPS_FIX_TYPE_STATIC
PPP = mavlink2.GPS_FIX_TYPE_PPP


def gps1(fix: int, satellites: int) -> Any:
    return mavlink2.MAVLink_gps_raw_int_message(
        0, fix, -353632620, 1491652370, 584000, 121, 200, 0, 0, satellites
    )


def gps2(fix: int, satellites: int) -> Any:
    return mavlink2.MAVLink_gps2_raw_message(
        0, fix, -353632620, 1491652370, 584000, 70, 120, 0, 0, satellites, 1, 0
    )


def chosen(first: tuple[int, int] | None, second: tuple[int, int] | None) -> str | None:
    latest = {}
    if first is not None:
        latest["GPS_RAW_INT"] = gps1(*first)
    if second is not None:
        latest["GPS2_RAW"] = gps2(*second)
    fix = choose(latest, None, now=0.0)
    return None if fix is None else fix.source


RANKED = [NO_GPS, FIX_2D, FIX_3D, DGPS, PPP, RTK_FLOAT, RTK_FIXED]


@pytest.mark.parametrize(("worse", "better"), list(itertools.pairwise(RANKED)))
def test_the_better_fix_wins_whatever_the_satellites(worse: int, better: int) -> None:
    assert chosen((worse, 30), (better, 5)) == "GPS2_RAW"
    assert chosen((better, 5), (worse, 30)) == "GPS_RAW_INT"


def test_rtk_fixed_beats_float_beats_dgps_beats_3d_beats_2d() -> None:
    fixes = [PositionFix(f"S{fix}", fix, 10) for fix in (FIX_2D, DGPS, RTK_FLOAT, FIX_3D)]
    assert best(fixes) == PositionFix(f"S{RTK_FLOAT}", RTK_FLOAT, 10)
    fixes.append(PositionFix("rtk", RTK_FIXED, 4))
    assert best(fixes) == PositionFix("rtk", RTK_FIXED, 4)


def test_no_fix_counts_as_no_gps_and_static_as_3d() -> None:
    assert chosen((NO_FIX, 3), (NO_GPS, 9)) == "GPS2_RAW"  # equal rank: more satellites
    assert chosen((STATIC, 10), (FIX_3D, 10)) == "GPS_RAW_INT"  # equal: the first receiver
    assert chosen((STATIC, 10), (DGPS, 4)) == "GPS2_RAW"
    assert chosen((99, 40), (FIX_2D, 4)) == "GPS2_RAW"  # an unknown fix type is no fix


def test_equal_fixes_go_to_more_satellites_then_to_the_first_receiver() -> None:
    assert chosen((FIX_3D, 9), (FIX_3D, 14)) == "GPS2_RAW"
    assert chosen((FIX_3D, 14), (FIX_3D, 9)) == "GPS_RAW_INT"
    assert chosen((FIX_3D, 12), (FIX_3D, 12)) == "GPS_RAW_INT"
    assert chosen((FIX_3D, 255), (FIX_3D, 1)) == "GPS2_RAW"  # 255: satellites unknown


def test_a_single_receiver_is_chosen_even_without_a_fix() -> None:
    assert chosen((NO_FIX, 0), None) == "GPS_RAW_INT"
    assert chosen(None, (FIX_2D, 5)) == "GPS2_RAW"
    assert chosen(None, None) is None


def test_stale_receivers_are_left_out() -> None:
    latest = {"GPS_RAW_INT": gps1(FIX_3D, 10), "GPS2_RAW": gps2(RTK_FIXED, 18)}
    timeouts = PositionTimeouts(stale_after_s=2.0)
    fresh = {"GPS_RAW_INT": 100.0, "GPS2_RAW": 100.0}
    assert [f.source for f in candidates(latest, fresh, 101.0, timeouts)] == [
        "GPS_RAW_INT",
        "GPS2_RAW",
    ]
    assert choose(latest, fresh, 102.0, timeouts) == PositionFix("GPS2_RAW", RTK_FIXED, 18)
    # the RTK receiver went quiet: the primary takes over
    went_quiet = {"GPS_RAW_INT": 103.0, "GPS2_RAW": 100.0}
    assert choose(latest, went_quiet, 103.5, timeouts) == PositionFix("GPS_RAW_INT", FIX_3D, 10)
    # ... and comes back
    back = {"GPS_RAW_INT": 104.0, "GPS2_RAW": 104.2}
    assert choose(latest, back, 104.5, timeouts) == PositionFix("GPS2_RAW", RTK_FIXED, 18)
    # a message never timed (no arrival time) is not trusted once times are known
    assert choose(latest, {"GPS2_RAW": 104.0}, 104.5, timeouts) == PositionFix(
        "GPS2_RAW", RTK_FIXED, 18
    )
    assert choose(latest, fresh, 110.0, timeouts) is None


def test_the_snapshot_reports_the_chosen_source() -> None:
    latest = {"GPS_RAW_INT": gps1(FIX_3D, 10), "GPS2_RAW": gps2(RTK_FIXED, 255)}
    received_at = {"GPS_RAW_INT": 50.0, "GPS2_RAW": 50.0}
    state = snapshot(latest, True, received_at=received_at, receive_errors=7, now=51.0)
    assert (state.position_source, state.gps_fix, state.satellites) == ("GPS2_RAW", 6, None)
    assert state.fcu_receive_errors == 7
    state = snapshot(latest, True, received_at={"GPS_RAW_INT": 55.0, "GPS2_RAW": 50.0}, now=55.5)
    assert (state.position_source, state.gps_fix, state.satellites) == ("GPS_RAW_INT", 3, 10)
    # every receiver quiet: no source, no fix (a fix from a minute ago is no fix)
    state = snapshot(latest, False, received_at=received_at, now=110.0)
    assert (state.position_source, state.gps_fix, state.satellites) == (None, 0, None)
