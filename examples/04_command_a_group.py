"""Take several vehicles off with one call, then land them all with another.

    GCS_HUB=http://127.0.0.1:8000 GCS_TOKEN=... \\
        python examples/04_command_a_group.py [VEHICLE ...] [--altitude 10]

A group command goes to the vehicles named (every online vehicle without names),
concurrently, and answers with one result per vehicle: a vehicle refusing does not
hold back the others, so check each one.
"""

import argparse

import httpx
from hubclient import LiveFeed, check, connect

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("vehicles", nargs="*", help="vehicle ids (default: every online one)")
parser.add_argument("--altitude", type=float, default=10, help="metres above home")
args = parser.parse_args()


def group_command(api: httpx.Client, command: dict[str, object]) -> list[str]:
    """Send one command to the group; print each vehicle's result; return who accepted."""
    body = {"vehicle_ids": args.vehicles or None, "command": command}
    answer = check(api.post("/api/v1/fleet/commands", json=body))
    accepted = []
    for result in answer["results"]:
        outcome = result["outcome"] or {}
        if result["status_code"] == 200 and outcome["status"] == "accepted":
            accepted.append(result["vehicle_id"])
        # On a refusal `error` says why (and `violations` lists the broken safety rules).
        print(f"{result['vehicle_id']:12} {command['name']}:", result["error"] or outcome)
    return accepted


with connect() as api, LiveFeed(api) as feed:
    group = args.vehicles or [v["id"] for v in check(api.get("/api/v1/vehicles")) if v["connected"]]
    feed.wait_until(
        lambda: all(feed.state(vehicle).get("ready_to_fly") for vehicle in group),
        "every vehicle ready to fly",
    )
    flying = group_command(api, {"name": "takeoff", "altitude": args.altitude})
    if flying:
        feed.wait_until(
            lambda: all(feed.state(v)["alt_rel"] >= args.altitude - 1 for v in flying),
            "the climb",
        )
        print("airborne:", ", ".join(flying))
    # Land every vehicle of the group, flying or not: landing is never refused.
    landing = group_command(api, {"name": "land"})
    feed.wait_until(lambda: not any(feed.state(v)["armed"] for v in group), "every landing")
    print("landed and disarmed:", ", ".join(group))
    if sorted(flying) != sorted(group) or sorted(landing) != sorted(group):
        raise SystemExit("error: not every vehicle took off and landed (see above)")
