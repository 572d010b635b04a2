"""Flying by hand through the hub: the lease, the 25 Hz stream, the agent's deadman, on
the ArduPilot copter hovering at 10 m (the package's `flying` fleet, conftest.py).

Real hub, simulator and agent processes on loopback, the simulator at real time so that
the agent's 0.5 s deadman (wall clock) is 0.5 s of simulated flight.
"""

from __future__ import annotations

import json
import math
import threading
import time
from typing import Any

import pytest

from gcs.launcher import LocalFleet
from tests.support.api import access_token, api_client, send_command
from tests.support.manual_flight import (
    OPERATOR_PASSWORD,
    PX4_VEHICLE,
    metres_moved,
    set_param,
)
from tests.support.pilots import VEHICLE, Pilot
from tests.support.waiting import poll_until
from tests.support.watcher import FleetWatcher, ready

pytestmark = [pytest.mark.integration, pytest.mark.slow]


def test_the_agent_refuses_a_lease_the_autopilot_would_ignore(
    flying: tuple[LocalFleet, str],
) -> None:
    """ArduPilot drops MANUAL_CONTROL from any system but SYSID_MYGCS (255 by default;
    the agent is 254) and ignores overrides with RC_OVERRIDE_TIME 0; PX4 drops it with
    COM_RC_IN_MODE 0 (RC only) or 4. The lease is refused with the reason, and frees."""
    fleet, token = flying
    base = fleet.plan.hub_http
    with api_client(base, token) as api:
        pilot = Pilot(base, token)
        px4 = Pilot(base, token, vehicle=PX4_VEHICLE)
        try:
            # Browser control opens only with a lease, never by a bare REST command.
            bare = api.post(f"/api/v1/vehicles/{VEHICLE}/commands", json={"name": "manual_start"})
            assert bare.status_code == 422, bare.text
            assert "comes with the manual-control lease" in bare.text
            set_param(api, VEHICLE, "SYSID_MYGCS", 255)  # ArduPilot's default
            asked_at = time.monotonic()
            refused = pilot.take()
            # The pilot hears it at once, in words, with the change that lifts it...
            assert time.monotonic() - asked_at < 1.0, "the refusal took over a second"
            assert refused["type"] == "lease_refused", refused
            assert refused["action"] == "acquire"
            assert "SYSID_MYGCS = 255" in refused["reason"]
            assert "set SYSID_MYGCS to 254" in refused["reason"]
            assert refused["fix"] == {"param": "SYSID_MYGCS", "value": 254}
            # ...and every dashboard's event feed says it too, within a second.
            poll_until(lambda: pilot.events("admin may not take manual control"), 1, "the event")
            [event] = pilot.events("admin may not take manual control")
            assert event["vehicle_id"] == VEHICLE
            assert event["kind"] == "manual"
            assert event["severity"] == 4
            assert "set SYSID_MYGCS to 254" in event["text"]
            # A second click is told again, but stored once (not a flight-log row a click).
            again = pilot.take()
            assert again["type"] == "lease_refused"
            assert "SYSID_MYGCS" in again["reason"]
            set_param(api, VEHICLE, "SYSID_MYGCS", 254)
            set_param(api, VEHICLE, "RC_OVERRIDE_TIME", 0)
            said_before = pilot.events("SYSID_MYGCS = 255")
            pilot.received.clear()
            refused = pilot.take()
            assert "RC_OVERRIDE_TIME is 0" in refused["reason"], refused
            assert refused["fix"] == {"param": "RC_OVERRIDE_TIME", "value": 3}
            # This refusal's event comes after any the second click stored: one was.
            poll_until(lambda: pilot.events("RC_OVERRIDE_TIME is 0"), 1, "the second event")
            assert len(said_before + pilot.events("SYSID_MYGCS = 255")) == 1
            set_param(api, VEHICLE, "RC_OVERRIDE_TIME", 3)
            # Nothing was granted, nothing changed on the vehicle: it still hovers in GUIDED.
            assert pilot.leases("admin") == []
            with FleetWatcher(base, token) as watcher:
                watcher.wait_until(ready(VEHICLE), 10, "the fleet")
                assert watcher.state(VEHICLE)["mode"] == "GUIDED"

            set_param(api, PX4_VEHICLE, "COM_RC_IN_MODE", 0)
            refused = px4.take()
            assert "COM_RC_IN_MODE = 0" in refused["reason"], refused
            assert refused["fix"] == {"param": "COM_RC_IN_MODE", "value": 3}
            set_param(api, PX4_VEHICLE, "COM_RC_IN_MODE", 3)
            # PX4's manual-control-loss failsafe would turn the deadman's Hold into a
            # Return (NAV_RCL_ACT 2) unless COM_RCL_EXCEPT exempts Hold (bit 1): the fix
            # adds that bit to what is set (here bit 0, Mission).
            set_param(api, PX4_VEHICLE, "COM_RCL_EXCEPT", 1)
            px4.received.clear()
            refused = px4.take()
            assert "COM_RCL_EXCEPT = 1 does not exempt Hold" in refused["reason"], refused
            assert "NAV_RCL_ACT = 2, Return" in refused["reason"]
            assert "set COM_RCL_EXCEPT to 3" in refused["reason"]
            assert refused["fix"] == {"param": "COM_RCL_EXCEPT", "value": 3}
            set_param(api, PX4_VEHICLE, "COM_RCL_EXCEPT", 3)
            px4.received.clear()
            granted = px4.take()
            assert granted["type"] == "lease", granted
            assert granted["holder"] == "admin"
            px4.control("release")
            poll_until(lambda: px4.leases(None, "released by admin"), 10, "the release")
        finally:
            pilot.close()
            px4.close()


def test_taking_a_hovering_arducopter_holds_its_height_until_the_first_frame(
    flying: tuple[LocalFleet, str],
) -> None:
    """ArduCopter's LOITER flies the transmitter's throttle until an override comes (SITL's
    sits at its minimum: a real copter sank 2.8 m). The agent streams centred sticks at
    mid throttle from the lease's start, so a first frame 1.5 s late costs no height."""
    fleet, token = flying
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher:
        watcher.wait_until(ready(VEHICLE), 10, "the fleet")
        start_alt = watcher.state(VEHICLE)["alt_rel"]
        assert start_alt > 9.0
        pilot = Pilot(base, token)
        try:
            assert pilot.take()["holder"] == "admin"
            granted_at = time.monotonic()
            heights: list[float] = []

            def late_first_frame(vehicles: dict[str, Any]) -> bool:
                state = vehicles[VEHICLE]["state"]
                if state["mode"] == "LOITER":
                    heights.append(state["alt_rel"])
                return time.monotonic() - granted_at > 1.5 and len(heights) > 2

            watcher.wait_until(late_first_frame, 10, "1.5 s of the lease in LOITER")
            pilot.stick(0)  # the browser's first frame, late
            lost = start_alt - min(heights)
            assert lost < 0.3, (start_alt, heights)
            pilot.control("release")
            poll_until(lambda: pilot.leases(None, "released by admin"), 10, "the release")
        finally:
            pilot.close()


def test_input_without_the_lease_is_refused(flying: tuple[LocalFleet, str]) -> None:
    fleet, token = flying
    pilot = Pilot(fleet.plan.hub_http, token)
    try:
        pilot.stick(1000)
        refusal = poll_until(lambda: pilot.said("error"), 5, "the hub's refusal")[0]
        assert refusal["code"] == "forbidden"
        assert "does not hold the manual-control lease" in refusal["message"]
    finally:
        pilot.close()


def test_bad_frames_are_refused_counted_and_never_flown(flying: tuple[LocalFleet, str]) -> None:
    """Axes outside MANUAL_CONTROL's ranges and NaN are refused by the wire's schema
    (each one answered, and counted towards the feed's bad-frame limit), before any
    lease check: they cannot be forwarded, for there is no frame to forward."""
    fleet, token = flying
    pilot = Pilot(fleet.plan.hub_http, token)
    try:
        assert pilot.take()["holder"] == "admin"
        bad = [{"x": 1001, "y": 0}, {"x": float("nan"), "y": 0}, {"x": 0, "y": 0, "z": -1}]
        for axes in bad:
            pilot.seq += 1
            frame = {"type": "manual", "vehicle_id": VEHICLE, "seq": pilot.seq, "axes": axes}
            pilot.socket.send(json.dumps(frame))
        refusals = poll_until(
            lambda: (
                [m for m in pilot.said("error") if m["code"] == "invalid_message"]
                if len(pilot.said("error")) >= len(bad)
                else []
            ),
            5,
            "the refusals",
        )
        assert len(refusals) == len(bad), refusals
        assert any("axes.x" in m["message"] for m in refusals), refusals
        assert any("axes.z" in m["message"] for m in refusals), refusals
        # None renewed the lease: with no good frame, it expires.
        poll_until(lambda: pilot.leases(None, "expired"), 10, "the lease to expire")
    finally:
        pilot.close()


def test_sticks_fly_the_vehicle_and_silence_holds_it(flying: tuple[LocalFleet, str]) -> None:
    fleet, token = flying
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher:
        watcher.wait_until(ready(VEHICLE), 10, "the fleet")
        pilot = Pilot(base, token, source="touch")  # a steady on-screen stick
        try:
            lease = pilot.take()
            assert lease["holder"] == "admin"
            before = dict(watcher.state(VEHICLE))
            heading = math.radians(before["heading_deg"])

            stop = threading.Event()
            streamer = threading.Thread(target=pilot.stream, args=(stop, 600), daemon=True)
            streamer.start()  # 60 % forward at 25 Hz
            try:
                after = watcher.wait_until(
                    lambda v: math.hypot(*metres_moved(before, v[VEHICLE]["state"])) > 8.0,
                    10,
                    f"{VEHICLE} to fly on the sticks",
                )[VEHICLE]["state"]
                assert after["mode"] == "LOITER"  # the agent switched to the pilot mode
                # The agent echoes flown frames to the holder: the input-to-vehicle delay.
                echo = poll_until(lambda: pilot.said("manual_echo"), 5, "an echo")[-1]
                assert echo["vehicle_id"] == VEHICLE
                delay_ms = time.monotonic() * 1000 - echo["sent_ms"]
                assert 0 < delay_ms < 2000, delay_ms
            finally:
                stop.set()
                streamer.join(5)
            stopped_at = time.monotonic()
            north, east = metres_moved(before, after)
            moved = math.hypot(north, east)
            # Forward: along the heading the vehicle had when the sticks moved.
            along = north * math.cos(heading) + east * math.sin(heading)
            assert along > 0.9 * moved, (north, east, before["heading_deg"])

            # The stream stops: the agent's deadman holds the vehicle.
            held = watcher.wait_until(
                lambda v: v[VEHICLE]["state"]["mode"] == "BRAKE", 5, "the deadman's BRAKE"
            )
            assert held

            def stopped_events() -> list[dict[str, Any]]:
                return [
                    e for e in watcher.events if e["kind"] == "manual" and "stopped" in e["text"]
                ]

            watcher.wait_until(lambda v: bool(stopped_events()), 5, "the deadman's event")
            events = stopped_events()
            silence = float(events[-1]["text"].split("stopped for ")[1].split(" s")[0])
            assert 0.5 <= silence <= 0.6, events[-1]["text"]
            # And the hub ended the lease, so the stream cannot take it back unasked.
            poll_until(lambda: pilot.leases(None, "stopped for"), 5, "the lease to end")
            assert time.monotonic() - stopped_at < 5
        finally:
            pilot.close()


def test_a_mode_change_the_agent_did_not_make_ends_the_lease(
    flying: tuple[LocalFleet, str],
) -> None:
    """The RC pilot's mode switch outranks the browser; here the change comes from
    another ground station's set_mode, which the agent can no more tell apart from the
    transmitter than ArduPilot's HEARTBEAT lets it."""
    fleet, token = flying
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher, api_client(base, token) as api:
        watcher.wait_until(ready(VEHICLE), 10, "the fleet")
        pilot = Pilot(base, token)
        stop = threading.Event()
        streamer = threading.Thread(target=pilot.stream, args=(stop, 0), daemon=True)
        try:
            assert pilot.take()["holder"] == "admin"
            streamer.start()
            watcher.wait_until(
                lambda v: v[VEHICLE]["state"]["mode"] == "LOITER", 5, "the pilot mode"
            )
            switched = send_command(api, VEHICLE, name="set_mode", mode="RTL")
            assert switched["status"] == "accepted"
            poll_until(lambda: pilot.leases(None, "changed to RTL"), 5, "the lease to end")
            # Frames still streaming are now refused at the hub, never forwarded.
            poll_until(
                lambda: [m for m in pilot.said("error") if "lease" in m["message"]],
                5,
                "the refusal of the stream",
            )
            # The stream still running did not take the vehicle back into LOITER.
            watcher.wait_until(lambda v: v[VEHICLE]["state"]["mode"] == "RTL", 5, "RTL")
        finally:
            stop.set()
            if streamer.is_alive():
                streamer.join(5)
            pilot.close()


def test_a_frozen_input_holds_the_vehicle(flying: tuple[LocalFleet, str]) -> None:
    """The complaint: a gamepad froze while the page kept streaming its last values, so
    the deadman never fired. Fresh frames (new seq, 25 Hz) with the same off-centre
    values from a gamepad hold the vehicle after the frozen time (3 s)."""
    fleet, token = flying
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher:
        watcher.wait_until(ready(VEHICLE), 10, "the fleet")
        pilot = Pilot(base, token, source="gamepad")
        stop = threading.Event()
        streamer = threading.Thread(target=pilot.stream, args=(stop, 300), daemon=True)
        try:
            assert pilot.take()["holder"] == "admin"
            streamer.start()  # the same 30 % forward, forever
            started = time.monotonic()
            watcher.wait_until(
                lambda v: v[VEHICLE]["state"]["mode"] == "BRAKE", 10, "the frozen input's BRAKE"
            )
            held_after = time.monotonic() - started
            assert 3.0 <= held_after <= 5.0, held_after
            assert streamer.is_alive()  # the stream never stopped: the values froze
            ended = poll_until(lambda: pilot.leases(None, "frozen"), 5, "the lease to end")
            assert "the same off-centre values" in ended[-1]["reason"]
            poll_until(lambda: pilot.refusals("does not hold"), 5, "the stream refused")
        finally:
            stop.set()
            if streamer.is_alive():
                streamer.join(5)
            pilot.close()


def test_one_pilot_at_a_time_and_an_admin_revokes(flying: tuple[LocalFleet, str]) -> None:
    fleet, token = flying
    base = fleet.plan.hub_http
    operator_token = access_token(base, "pilot", OPERATOR_PASSWORD)
    with FleetWatcher(base, token) as watcher:
        watcher.wait_until(ready(VEHICLE), 10, "the fleet")
        operator = Pilot(base, operator_token)
        admin = Pilot(base, token)
        stop = threading.Event()
        streamer = threading.Thread(target=operator.stream, args=(stop, 0), daemon=True)
        try:
            assert operator.take()["holder"] == "pilot"
            streamer.start()
            # Every dashboard is told who flies it, the second operator among them.
            poll_until(lambda: admin.leases("pilot"), 5, "the admin's dashboard to see it")
            refused = admin.take()
            assert refused["type"] == "lease_refused", refused
            assert f"{VEHICLE} is flown by hand by pilot" in refused["reason"]
            assert refused["fix"] is None  # no parameter lifts this one

            admin.control("revoke")
            ended = poll_until(lambda: operator.leases(None, "revoked by admin"), 5, "revoked")
            assert ended[-1]["holder"] is None
            # The hub told the agent: the vehicle holds, and the stream goes nowhere.
            watcher.wait_until(lambda v: v[VEHICLE]["state"]["mode"] == "BRAKE", 5, "BRAKE")
            poll_until(lambda: operator.refusals("does not hold"), 5, "the stream refused")
        finally:
            stop.set()
            if streamer.is_alive():
                streamer.join(5)
            operator.close()
            admin.close()


def test_a_lease_without_input_expires(flying: tuple[LocalFleet, str]) -> None:
    fleet, token = flying
    base = fleet.plan.hub_http
    with FleetWatcher(base, token) as watcher:
        watcher.wait_until(ready(VEHICLE), 10, "the fleet")
        pilot = Pilot(base, token)
        try:
            assert pilot.take()["holder"] == "admin"
            granted_at = time.monotonic()
            watcher.wait_until(lambda v: v[VEHICLE]["state"]["mode"] == "LOITER", 5, "LOITER")
            ended = poll_until(lambda: pilot.leases(None, "expired"), 10, "the expiry")
            assert 2.0 <= time.monotonic() - granted_at < 5.0
            assert "no input from admin for 2 s" in ended[-1]["reason"]
            watcher.wait_until(lambda v: v[VEHICLE]["state"]["mode"] == "BRAKE", 5, "BRAKE")
        finally:
            pilot.close()
