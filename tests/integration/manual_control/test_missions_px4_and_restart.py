"""Flying by hand through the hub, after the lease and stick tests: a mission taken by
hand and resumed on ArduPilot and PX4, the stream's buttons, PX4's deadman Hold, and last
a hub restart with a lease held (the package's `flying` fleet, conftest.py).
"""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

from gcs.launcher import LocalFleet
from tests.support.api import access_token, api_client, send_command
from tests.support.hubs import TEST_HUB_ENV
from tests.support.manual_flight import (
    PX4_VEHICLE,
    pause_by_hand_and_resume,
    press,
    set_param,
    start_a_mission,
)
from tests.support.pilots import VEHICLE, Pilot
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, ready

pytestmark = [pytest.mark.integration, pytest.mark.slow]


def test_a_mission_pauses_under_the_lease_and_resumes_after(
    flying: tuple[LocalFleet, str],
) -> None:
    fleet, token = flying
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(VEHICLE), 10, "the fleet")
        start_a_mission(api, watcher, VEHICLE, mode="AUTO", first_north_m=15, alt=10)
        pause_by_hand_and_resume(api, watcher, Pilot(base, token), mode="AUTO", pilot_mode="LOITER")


def test_the_select_and_hold_buttons(flying: tuple[LocalFleet, str]) -> None:
    """The seed's select button: ignored high up; on the ground it arms, and disarms
    again. The hold button holds the vehicle and gives control back."""
    fleet, token = flying
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher:
        watcher.wait_until(ready(VEHICLE), 10, "the fleet")
        watcher.wait_until(ready(PX4_VEHICLE), 10, "the PX4 copter")
        high = Pilot(base, token)
        ground = Pilot(base, token, vehicle=PX4_VEHICLE)
        stop = threading.Event()
        streams = [
            threading.Thread(target=pilot.stream, args=(stop, 0), daemon=True)
            for pilot in (high, ground)
        ]
        try:
            assert high.take()["holder"] == "admin"
            assert ground.take()["holder"] == "admin"
            for stream in streams:
                stream.start()
            # At 10 m the select button does nothing but say so.
            press(high, 1)
            watcher.wait_until(
                lambda v: any("select ignored at" in e["text"] for e in watcher.events),
                5,
                "select ignored high up",
            )
            assert watcher.state(VEHICLE)["mode"] == "LOITER"
            # On the ground, disarmed: select arms; pressed again, it disarms.
            assert watcher.state(PX4_VEHICLE)["armed"] is False
            press(ground, 1)
            watcher.wait_until(lambda v: v[PX4_VEHICLE]["state"]["armed"], 10, "armed")
            press(ground, 1)
            watcher.wait_until(lambda v: not v[PX4_VEHICLE]["state"]["armed"], 10, "disarmed again")
            # The hold button: BRAKE, and the lease goes back.
            press(high, 2)
            watcher.wait_until(lambda v: v[VEHICLE]["state"]["mode"] == "BRAKE", 5, "BRAKE")
            poll_until(lambda: high.leases(None, "hold button pressed"), 5, "the lease ended")
        finally:
            stop.set()
            for stream in streams:
                if stream.is_alive():
                    stream.join(5)
            ground.control("release")
            high.close()
            ground.close()


def test_a_flying_px4_is_taken_by_hand_and_its_deadman_hold_stays_a_hold(
    flying: tuple[LocalFleet, str],
) -> None:
    """PX4 refuses POSCTL in the air (TEMPORARILY_REJECTED) until it has had manual
    input: the agent's centred sticks come first. When the stream stops, the deadman's
    Hold stays a hold past PX4's manual-control-loss failsafe (COM_RC_LOSS_T +
    COM_FAIL_ACT_T, shortened to 1 s here), for COM_RCL_EXCEPT exempts Hold."""
    fleet, token = flying
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(PX4_VEHICLE), 10, "the PX4 vehicle")
        set_param(api, PX4_VEHICLE, "COM_RCL_EXCEPT", 2)  # as the refusal's fix sets it
        set_param(api, PX4_VEHICLE, "COM_FAIL_ACT_T", 1.0)
        assert send_command(api, PX4_VEHICLE, name="arm")["status"] == "accepted"
        assert send_command(api, PX4_VEHICLE, name="takeoff", altitude=4)["status"] == "accepted"
        watcher.wait_until(
            lambda v: (
                v[PX4_VEHICLE]["state"]["mode"] == "LOITER"
                and (v[PX4_VEHICLE]["state"]["alt_rel"] or 0) > 3.5
            ),
            60,
            "the PX4 vehicle hovering in Hold",
        )
        pilot = Pilot(base, token, vehicle=PX4_VEHICLE, source="touch")
        stop = threading.Event()
        streamer = threading.Thread(target=pilot.stream, args=(stop, 0), daemon=True)
        try:
            lease = pilot.take()
            assert lease["type"] == "lease", lease
            assert lease["holder"] == "admin"
            streamer.start()
            watcher.wait_until(
                lambda v: v[PX4_VEHICLE]["state"]["mode"] == "POSCTL", 5, "Position mode"
            )
            poll_until(lambda: pilot.said("manual_echo"), 5, "a flown frame")
            stop.set()
            streamer.join(5)
            watcher.wait_until(
                lambda v: v[PX4_VEHICLE]["state"]["mode"] == "LOITER", 5, "the deadman's Hold"
            )
            poll_until(lambda: pilot.leases(None, "stopped for"), 5, "the lease to end")
            # Past the failsafe's 1.5 s from the last frame (and a second more), still Hold.
            modes: set[str] = set()

            def past_the_failsafe(vehicles: dict[str, Any]) -> bool:
                modes.add(vehicles[PX4_VEHICLE]["state"]["mode"])
                return time.monotonic() - pilot.last_sent_at > 2.5

            watcher.wait_until(past_the_failsafe, 10, "the failsafe's time to pass")
            assert modes == {"LOITER"}, modes
        finally:
            stop.set()
            if streamer.is_alive():
                streamer.join(5)
            pilot.close()


def test_a_px4_mission_pauses_under_the_lease_and_resumes_after(
    flying: tuple[LocalFleet, str],
) -> None:
    """PX4's mission mode is MISSION (AUTO.MISSION in PX4's terms): taking the sticks in it
    pauses the mission, the lease and its release offer MISSION to resume it, and MISSION
    carries on from the item it was flying to."""
    fleet, token = flying
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(PX4_VEHICLE), 10, "the PX4 vehicle")
        # Mission and Hold exempt from PX4's manual-control-loss failsafe: an earlier
        # test's stick input has stopped, and the mission must not turn into a Return.
        set_param(api, PX4_VEHICLE, "COM_RCL_EXCEPT", 3)
        if not watcher.state(PX4_VEHICLE)["armed"]:  # run alone: fly it up first
            assert send_command(api, PX4_VEHICLE, name="arm")["status"] == "accepted"
            taken_off = send_command(api, PX4_VEHICLE, name="takeoff", altitude=4)
            assert taken_off["status"] == "accepted", taken_off
        watcher.wait_until(
            lambda v: (v[PX4_VEHICLE]["state"]["alt_rel"] or 0) > 3.5, 60, "the PX4 vehicle up"
        )
        start_a_mission(api, watcher, PX4_VEHICLE, mode="MISSION", first_north_m=10, alt=5)
        pause_by_hand_and_resume(
            api,
            watcher,
            Pilot(base, token, vehicle=PX4_VEHICLE),
            mode="MISSION",
            pilot_mode="POSCTL",
            paused_event="the mission is paused (MISSION resumes it)",
        )


def test_a_lease_survives_a_hub_restart_only_as_revoked(flying: tuple[LocalFleet, str]) -> None:
    """Last: it restarts the hub. The hub is killed with a lease held; the restarted hub
    reports that lease revoked to every dashboard, refuses the old pilot's stream, and
    the agent's deadman held the vehicle meanwhile."""
    fleet, token = flying
    base = fleet.plan.hub_http
    pilot = Pilot(base, token)
    try:
        assert pilot.take()["holder"] == "admin"
        for _ in range(5):
            pilot.stick(0)
    finally:
        pilot.close()
    fleet.kill("hub")
    fleet.start_hub(TEST_HUB_ENV)
    fleet.wait_until_ready()
    token = access_token(base, "admin", fleet.plan.admin_password)
    with FleetWatcher(base, token) as watcher:
        watcher.wait_until(ready(VEHICLE), 30, "the agent back")
        # The deadman, with no hub (the first state seen may predate it: waited on).
        watcher.wait_until(lambda v: v[VEHICLE]["state"]["mode"] == "BRAKE", 15, "BRAKE")
        pilot = Pilot(base, token)
        try:
            revoked = poll_until(
                lambda: pilot.leases(None, "revoked: the hub restarted"), 10, "the revocation"
            )
            assert "while admin held it" in revoked[-1]["reason"]
            pilot.seq = 1000
            pilot.stick(500)
            poll_until(lambda: pilot.refusals("does not hold"), 5, "the old stream refused")
        finally:
            pilot.close()
