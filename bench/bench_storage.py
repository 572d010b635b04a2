"""Storage benchmark: telemetry write throughput and the 1-hour downsample query time,
on SQLite (the embedded default) and the PostgreSQL server on 127.0.0.1.

    .venv/bin/python bench/bench_storage.py [--samples 50000]

Prints figures; asserts nothing. The machine is shared and small (2 cores), so each
figure is the median of several runs.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from backend.storage.database import make_engine, migrate
from backend.storage.logbook import Logbook
from backend.storage.records import TelemetryEnvelope
from backend.storage.repository import Repository
from protocol.messages import PROTOCOL_VERSION, Hello, Telemetry, VehicleState
from tests.conftest import scratch_postgres

BATCH = 500  # the hub writer's default batch
HOUR_AT_10HZ = 36_000


def _samples(vehicle: str, count: int, start: float) -> list[TelemetryEnvelope]:
    return [
        TelemetryEnvelope(
            vehicle,
            "bench",
            Telemetry(
                seq=i,
                time=start + i / 10,
                state=VehicleState(
                    armed=True,
                    mode="AUTO",
                    lat=-35.36 + i * 1e-7,
                    lon=149.16,
                    alt_rel=50 + 30 * math.sin(i / 900),
                    alt_msl=634.0,
                    groundspeed=5.0,
                    heading_deg=90.0,
                    battery_remaining=80.0,
                    gps_fix=3,
                    satellites=12,
                ),
            ),
        )
        for i in range(count)
    ]


def _hello(vehicle: str) -> Hello:
    return Hello(
        protocol=PROTOCOL_VERSION,
        vehicle_id=vehicle,
        autopilot="ardupilot",
        vehicle_type="multirotor",
        system_id=1,
        agent_version="bench",
        stream_id="bench",
    )


def run(url: str, label: str, samples: int) -> None:
    engine = make_engine(url)
    migrate(engine)
    repository = Repository(engine)
    rates = []
    for run_index in range(3):
        vehicle = f"w{run_index}"
        repository.upsert_vehicle(_hello(vehicle), now=0)
        batch = _samples(vehicle, samples, 0)
        started = time.perf_counter()
        for offset in range(0, samples, BATCH):
            repository.insert_telemetry(batch[offset : offset + BATCH])
        rates.append(samples / (time.perf_counter() - started))
    print(
        f"{label:10} write: median {statistics.median(rates):9,.0f} samples/s "
        f"(runs: {', '.join(f'{r:,.0f}' for r in rates)}; batches of {BATCH})"
    )

    repository.upsert_vehicle(_hello("hour"), now=0)
    hour = _samples("hour", HOUR_AT_10HZ, 1_000_000)
    for offset in range(0, HOUR_AT_10HZ, 5000):
        repository.insert_telemetry(hour[offset : offset + 5000])
    logbook = Logbook(engine)
    timings = []
    for _ in range(7):
        started = time.perf_counter()
        rows = logbook.series("hour", 1_000_000, 1_000_000 + 3600, 1000, "alt_rel")
        timings.append((time.perf_counter() - started) * 1000)
    assert len(rows) == 1000
    print(
        f"{label:10} 1-hour downsample (36,000 → 1,000 points): median "
        f"{statistics.median(timings):.0f} ms (min {min(timings):.0f}, "
        f"max {max(timings):.0f}; bar 200 ms)"
    )
    engine.dispose()


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=50_000)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        run(f"sqlite:///{folder}/bench.sqlite3", "SQLite", args.samples)
    with scratch_postgres() as url:
        run(url, "PostgreSQL", args.samples)


if __name__ == "__main__":
    main()
