"""The hub's Prometheus metrics, served at ``/metrics`` (backend/api/metrics.py).

One module holds every metric so that any layer can count without importing the layers
above it: realtime, storage and control all import from here, and this imports nothing of
the hub. The metrics live in prometheus-client's default registry, which also carries the
process's own CPU, memory and file descriptors (``process_*``). Several hubs in one
process (the tests) share these figures; a deployment runs one hub per process.

``gcs_rejected_frames_total`` counts every frame or body a surface refused as malformed or
against its rules (undecodable JSON, an invalid message, a bad scan, a frame over the
size limit, a bad first frame, manual input without the lease), by surface: a probe or a
broken peer shows up as a rising rate here rather than only in the log.
"""

from __future__ import annotations

from typing import Literal, get_args

from prometheus_client import Counter, Gauge, Histogram

from protocol.messages import STATE_BOUNDS

# agent_ws: /api/v1/agent/ws; client_ws: /api/v1/ws (dashboards, integrations);
# agent_scan: an agent's binary LIDAR frames; client_manual: manual-control input;
# bus_command: a command routed over NATS that names no sender the database knows.
Surface = Literal["agent_ws", "client_ws", "agent_scan", "client_manual", "bus_command"]

REJECTED_FRAMES = Counter(
    "gcs_rejected_frames",
    "Frames refused as malformed or invalid, by the surface that refused them",
    ["surface"],
)
CONNECTIONS = Gauge(
    "gcs_connections", "Open WebSocket connections, by kind (agent, dashboard).", ["kind"]
)
MESSAGES_IN = Counter(
    "gcs_messages_in_total", "Frames received on a WebSocket, by surface.", ["surface"]
)
MESSAGES_OUT = Counter(
    "gcs_messages_out_total", "Frames sent on a WebSocket, by surface.", ["surface"]
)
DROPPED = Counter(
    "gcs_dropped_total",
    "Live updates a client never got, by reason: 'coalesced' (a newer state replaced an "
    "unsent one, the slow-client policy), 'slow_client' (a feed closed for falling behind).",
    ["reason"],
)
QUEUE_DEPTH = Gauge(
    "gcs_queue_depth",
    "Records waiting, by queue: 'storage' (the writer's inbox), 'dashboard_max' (the most "
    "vehicle updates pending for any one client feed).",
    ["queue"],
)
TELEMETRY_REFUSED = Counter(
    "gcs_telemetry_refused",
    "Agents' telemetry samples refused and not stored because a value is physically "
    "impossible (protocol.messages.STATE_BOUNDS), by reason: the first field out of range.",
    ["reason"],
)
STORAGE_ROWS = Counter("gcs_storage_rows_total", "Telemetry samples committed to the database.")
STORAGE_BATCH_SECONDS = Histogram(
    "gcs_storage_batch_seconds",
    "Time to commit one writer batch.",
    buckets=(0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0),
)
STORAGE_WRITE_LAG = Gauge(
    "gcs_storage_write_lag_seconds",
    "Age of the oldest sample in the last committed batch when it committed: how far the "
    "store is behind the fleet.",
)
COMMAND_SECONDS = Histogram(
    "gcs_command_seconds",
    "Time from a command sent to an agent to its result, by outcome.",
    ["outcome"],
    buckets=(0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0, 30.0, 60.0),
)

SURVEY_PLANS_RUNNING = Gauge(
    "gcs_survey_plans_running",
    "Survey plans being computed in worker processes, or waiting for one, now.",
)
SURVEY_PLANS_STOPPED = Counter(
    "gcs_survey_plans_stopped",
    "Survey plans stopped before they finished, their worker killed, by reason (disconnect: "
    "the client went away; timeout: past survey_plan_timeout_s; shutdown: the hub stopped; "
    "died: the worker ended on its own).",
    ["reason"],
)


def count_rejected(surface: Surface) -> None:
    REJECTED_FRAMES.labels(surface=surface).inc()


# Every labelled series exists from the start, so a scrape shows zeros, not absences.
for _surface in get_args(Surface):
    REJECTED_FRAMES.labels(surface=_surface)
    MESSAGES_IN.labels(surface=_surface)
    MESSAGES_OUT.labels(surface=_surface)
for _kind in ("agent", "dashboard"):
    CONNECTIONS.labels(kind=_kind)
for _reason in ("coalesced", "slow_client"):
    DROPPED.labels(reason=_reason)
for _reason in ("disconnect", "timeout", "shutdown", "died"):
    SURVEY_PLANS_STOPPED.labels(reason=_reason)
for _field in STATE_BOUNDS:
    TELEMETRY_REFUSED.labels(reason=f"{_field}_out_of_range")
