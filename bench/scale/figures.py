"""The run's figures: percentiles, and the table the bench prints."""

from __future__ import annotations

import math
from typing import Any


def percentile(values: list[float], fraction: float) -> float:
    if not values:
        return math.nan
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(fraction * len(ordered)))]


def table(figures: dict[str, Any]) -> str:
    rows = [
        ("vehicles x rate", f"{figures['vehicles']} x {figures['rate_hz']:g} Hz"),
        (
            "dashboards / hubs / db",
            f"{figures['dashboards']} / {figures['hubs']} / {figures['database']}",
        ),
        ("sent / stored per s", f"{figures['sent_per_s']:g} / {figures['stored_per_s']:g}"),
        ("db lost / duplicates", f"{figures['db_lost']} / {figures['db_duplicates']}"),
        (
            "dash regressions / dup / final missing",
            f"{figures['dash_regressions']} / {figures['dash_duplicates']} / "
            f"{figures['dash_final_missing']}",
        ),
        (
            "agent->dashboard p50 / p95 / p99 ms",
            f"{figures['delay_p50_ms']} / {figures['delay_p95_ms']} / {figures['delay_p99_ms']}",
        ),
        ("agent->ack p50 / p99 ms", f"{figures['ack_p50_ms']} / {figures['ack_p99_ms']}"),
        (
            "dashboard frames/s, KiB/s",
            f"{figures['dash_frames_per_s']}, {figures['dash_kib_per_s']}",
        ),
        (
            "hub CPU mean / max %, RSS MiB",
            f"{figures['hub_cpu_mean_pct']} / "
            f"{figures['hub_cpu_max_pct']}, {figures['hub_rss_peak_mib']}",
        ),
        (
            "late send slots, load avg",
            f"{figures['late_send_slots']}, {figures['load_average_1m']}",
        ),
    ]
    width = max(len(name) for name, _ in rows)
    return "\n".join(f"{name:<{width}}  {value}" for name, value in rows)
