"""Take several vehicles off with one call, then land them all with another.

    GCS_HUB=http://127.0.0.1:8000 GCS_TOKEN=... \\
        python examples/04_command_a_group.py [VEHICLE ...] [--altitude 10]

A group command goes to the vehicles named (every online vehicle without names),
concurrently, and answers with one result per vehicle: a vehicle refusing does not
hold back the others, so check each one.
"""

import argparse
import asyncio
from typing import Any

from gcs_client import Hub, HubError

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("vehicles", nargs="*", help="vehicle ids (default: every online one)")
parser.add_argument("--altitude", type=float, default=10, help="metres above home")
args = parser.parse_args()


async def group_command(hub: Hub, name: str, **fields: Any) -> list[str]:
    """Send one command to the group; print each vehicle's result; return who accepted."""
    answer = await hub.fleet.command(name, args.vehicles or None, **fields)
    accepted = []
    for result in answer.results:
        outcome = result.outcome
        if result.status_code == 200 and outcome is not None and outcome.status == "accepted":
            accepted.append(result.vehicle_id)
        # On a refusal `error` says why (and `violations` lists the broken safety rules).
        print(f"{result.vehicle_id:12} {name}:", result.error or outcome)
    return accepted


async def fly() -> None:
    async with Hub.from_env() as hub, hub.watch() as fleet:
        group = args.vehicles or [v.id for v in await hub.vehicles.list() if v.connected]
        await fleet.wait_until(
            lambda: all(fleet.state(vehicle).ready_to_fly for vehicle in group),
            120,
            "every vehicle ready to fly",
        )
        flying = await group_command(hub, "takeoff", altitude=args.altitude)
        if flying:
            await fleet.wait_until(
                lambda: all((fleet.state(v).alt_rel or 0) >= args.altitude - 1 for v in flying),
                120,
                "the climb",
            )
            print("airborne:", ", ".join(flying))
        # Land every vehicle of the group, flying or not: landing is never refused.
        landing = await group_command(hub, "land")
        await fleet.wait_until(
            lambda: not any(fleet.state(v).armed for v in group), 120, "every landing"
        )
        print("landed and disarmed:", ", ".join(group))
        if sorted(flying) != sorted(group) or sorted(landing) != sorted(group):
            raise SystemExit("error: not every vehicle took off and landed (see above)")


try:
    asyncio.run(fly())
except HubError as error:
    raise SystemExit(f"error: {error}") from None
