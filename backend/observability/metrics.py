"""The hub's Prometheus counters.

``gcs_rejected_frames_total`` counts every frame or body a surface refused as malformed or
against its rules (undecodable JSON, an invalid message, a bad scan, a frame over the
size limit, a bad first frame), by surface: a probe or a broken peer shows up as a rising
rate here rather than only in the log.
"""

from __future__ import annotations

from typing import Literal

from prometheus_client import Counter

Surface = Literal["agent_ws", "client_ws", "agent_scan"]

REJECTED_FRAMES = Counter(
    "gcs_rejected_frames",
    "Frames refused as malformed or invalid, by the surface that refused them",
    ["surface"],
)


def count_rejected(surface: Surface) -> None:
    REJECTED_FRAMES.labels(surface=surface).inc()
