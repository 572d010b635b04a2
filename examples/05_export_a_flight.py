"""Download a flight: the newest one, or one vehicle's newest, as GeoJSON, CSV or .tlog.

    GCS_HUB=http://127.0.0.1:8000 GCS_TOKEN=... \\
        python examples/05_export_a_flight.py [--vehicle ID] [--format geojson] [--output DIR]

The hub finds flights (arm to disarm) by itself. A .tlog opens in QGroundControl,
MAVProxy and pymavlink's mavlogdump.py.
"""

import argparse
from pathlib import Path

from hubclient import check, connect

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--vehicle", help="a vehicle id (default: any)")
parser.add_argument("--format", choices=["geojson", "csv", "tlog"], default="geojson")
parser.add_argument("--output", type=Path, default=Path.cwd(), help="folder to write to")
args = parser.parse_args()

with connect() as api:
    query = {"vehicle_id": args.vehicle} if args.vehicle else {}
    page = check(api.get("/api/v1/flights", params=query))  # newest first
    flights = [flight for flight in page["flights"] if flight["end_time"] is not None]
    if not flights:
        raise SystemExit("error: no finished flight yet (fly one: 03_command_a_vehicle.py)")
    flight = flights[0]
    print(
        f"flight {flight['id']} of {flight['vehicle_id']}: {flight['duration_s']:.0f} s, "
        f"{flight['distance_m']:.0f} m, up to {flight['max_alt_m']:.1f} m"
    )

    path = args.output / f"{flight['vehicle_id']}_flight{flight['id']}.{args.format}"
    # Streamed: a long flight is never held in memory whole, here or in the hub.
    with api.stream("GET", f"/api/v1/flights/{flight['id']}/export.{args.format}") as answer:
        if not answer.is_success:
            answer.read()
            check(answer)
        with path.open("wb") as file:
            for chunk in answer.iter_bytes():
                file.write(chunk)
    print(f"wrote {path} ({path.stat().st_size} bytes)")
