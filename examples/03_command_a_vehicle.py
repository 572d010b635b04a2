"""Take one vehicle off, fly it to a point 30 m north, and land it, watching the feed.

    GCS_HUB=http://127.0.0.1:8000 GCS_TOKEN=... \\
        python examples/03_command_a_vehicle.py [VEHICLE] [--altitude 10]

Each command answers with the flight controller's verdict (accepted, or refused with
its reason); the live feed shows what the vehicle then does.
"""

import argparse

from hubclient import LiveFeed, accepted, check, connect

NORTH_DEG = 30 / 111_320  # 30 m of latitude

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("vehicle", nargs="?", help="a vehicle id (default: the first online)")
parser.add_argument("--altitude", type=float, default=10, help="metres above home")
args = parser.parse_args()

with connect() as api, LiveFeed(api) as feed:
    vehicle = args.vehicle or next(
        v["id"] for v in check(api.get("/api/v1/vehicles")) if v["connected"]
    )

    def command(**body: object) -> None:
        answer = check(api.post(f"/api/v1/vehicles/{vehicle}/commands", json=body))
        accepted(answer, f"{body['name']} on {vehicle}")
        print(f"{vehicle} {body['name']}: {answer['outcome']['message']}")

    # A take-off is refused until the autopilot's pre-arm checks pass (GPS, EKF).
    feed.wait_until(lambda: feed.state(vehicle).get("ready_to_fly"), f"{vehicle} ready to fly")
    command(name="takeoff", altitude=args.altitude)
    feed.wait_until(lambda: feed.state(vehicle)["alt_rel"] >= args.altitude - 1, "the climb")
    print(f"{vehicle} at {feed.state(vehicle)['alt_rel']:.1f} m")

    here = feed.state(vehicle)
    target = {"lat": here["lat"] + NORTH_DEG, "lon": here["lon"]}
    command(name="goto", altitude=args.altitude, **target)
    feed.wait_until(
        lambda: abs(feed.state(vehicle)["lat"] - target["lat"]) < NORTH_DEG / 10, "the point"
    )
    print(f"{vehicle} at {feed.state(vehicle)['lat']:.6f}, {feed.state(vehicle)['lon']:.6f}")

    command(name="land")
    feed.wait_until(lambda: not feed.state(vehicle)["armed"], f"{vehicle} to land and disarm")
    print(f"{vehicle} landed and disarmed")
