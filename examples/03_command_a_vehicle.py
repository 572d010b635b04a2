"""Take one vehicle off, fly it to a point 30 m north, and land it, watching the feed.

    GCS_HUB=http://127.0.0.1:8000 GCS_TOKEN=... \\
        python examples/03_command_a_vehicle.py [VEHICLE] [--altitude 10]

Each command waits for the flight controller's verdict: accepted, or `CommandRefused` with
its reason; the live feed (`hub.watch()`) shows what the vehicle then does.
"""

import argparse
import asyncio
from typing import Any

from gcs_client import Hub, HubError
from gcs_client.models import VehicleState

NORTH_DEG = 30 / 111_320  # 30 m of latitude

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("vehicle", nargs="?", help="a vehicle id (default: the first online)")
parser.add_argument("--altitude", type=float, default=10, help="metres above home")
args = parser.parse_args()


async def fly() -> None:
    async with Hub.from_env() as hub, hub.watch() as fleet:
        vehicle = args.vehicle or next(v.id for v in await hub.vehicles.list() if v.connected)

        async def command(name: str, **fields: Any) -> None:
            answer = await hub.vehicles.command(vehicle, name, **fields)
            print(f"{vehicle} {name}: {answer.outcome.message}")

        def state() -> VehicleState:
            return fleet.state(vehicle)

        # A take-off is refused until the autopilot's pre-arm checks pass (GPS, EKF).
        await fleet.wait_until(lambda: state().ready_to_fly, 120, f"{vehicle} ready to fly")
        await command("takeoff", altitude=args.altitude)
        await fleet.wait_until(
            lambda: (state().alt_rel or 0) >= args.altitude - 1, 120, "the climb"
        )
        print(f"{vehicle} at {state().alt_rel:.1f} m")

        here = state()
        assert here.lat is not None, "flying, so it has a position"
        assert here.lon is not None
        target = {"lat": here.lat + NORTH_DEG, "lon": here.lon}
        await command("goto", altitude=args.altitude, **target)
        await fleet.wait_until(
            lambda: abs((state().lat or 0) - target["lat"]) < NORTH_DEG / 10, 120, "the point"
        )
        print(f"{vehicle} at {state().lat:.6f}, {state().lon:.6f}")

        await command("land")
        await fleet.wait_until(lambda: not state().armed, 120, f"{vehicle} to land and disarm")
        print(f"{vehicle} landed and disarmed")


try:
    asyncio.run(fly())
except HubError as error:
    raise SystemExit(f"error: {error}") from None
