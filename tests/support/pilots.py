"""A pilot's stick stream to the hub, at the dashboard's 25 Hz."""

from __future__ import annotations

import json
import threading
import time
from typing import Any

from websockets.sync.client import ClientConnection, connect

from protocol.messages import CLIENT_WS_PATH
from tests.support.waiting import poll_until

VEHICLE = "sim_1"


RATE_HZ = 25.0


class Pilot:
    """A dashboard's socket that flies: sends frames, keeps what the hub says back."""

    def __init__(
        self, base_url: str, token: str, vehicle: str = VEHICLE, source: str = "program"
    ) -> None:
        self.vehicle = vehicle
        self.source = source
        url = base_url.replace("http://", "ws://") + CLIENT_WS_PATH
        self.socket: ClientConnection = connect(
            url, additional_headers={"Authorization": f"Bearer {token}"}
        )
        self.received: list[dict[str, Any]] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        self.seq = 0
        self.buttons = 0  # MANUAL_CONTROL's button bits in every frame streamed
        self.last_sent_at = 0.0

    def _read(self) -> None:
        try:
            for frame in self.socket:
                self.received.append(json.loads(frame))
        except Exception:
            return

    def said(self, kind: str) -> list[dict[str, Any]]:
        return [message for message in list(self.received) if message["type"] == kind]

    def control(self, action: str) -> None:
        self.socket.send(
            json.dumps({"type": "control", "vehicle_id": self.vehicle, "action": action})
        )

    def stick(self, x: int, y: int = 0, z: int = 500, r: int = 0) -> None:
        self.seq += 1
        axes = {"x": x, "y": y, "z": z, "r": r, "buttons": self.buttons}
        frame = {
            "type": "manual",
            "vehicle_id": self.vehicle,
            "seq": self.seq,
            "axes": axes,
            "source": self.source,
            "sent_ms": time.monotonic() * 1000,
        }
        self.socket.send(json.dumps(frame))

    def leases(self, holder: str | None = None, reason: str = "") -> list[dict[str, Any]]:
        """The lease states said so far with this holder and a reason containing ``reason``."""
        return [
            m
            for m in self.said("lease")
            if m["vehicle_id"] == self.vehicle and m["holder"] == holder and reason in m["reason"]
        ]

    def refusals(self, text: str) -> list[dict[str, Any]]:
        return [m for m in self.said("error") if text in m["message"]]

    def events(self, text: str) -> list[dict[str, Any]]:
        """The live feed's events so far whose text contains ``text``."""
        return [
            event
            for message in self.said("events")
            for event in message["events"]
            if text in event["text"]
        ]

    def take(self) -> dict[str, Any]:
        """Ask for the lease; the hub's answer (the new lease state, or the refusal)."""
        asked_at = len(self.received)
        self.control("acquire")

        def answer() -> list[dict[str, Any]]:
            return [
                m
                for m in list(self.received)[asked_at:]
                if m["type"] == "lease_refused" or (m["type"] == "lease" and m["holder"])
            ]

        return poll_until(answer, 30, "the lease or its refusal")[0]

    def stream(self, stop: threading.Event, x: int, z: int = 500) -> None:
        """Frames at RATE_HZ until ``stop``, paced on the monotonic clock (the pacing is
        the test's input, not a wait on the system under test)."""
        period = 1.0 / RATE_HZ
        next_at = time.monotonic()
        while not stop.is_set():
            self.stick(x, z=z)
            self.last_sent_at = time.monotonic()
            next_at += period
            stop.wait(max(0.0, next_at - time.monotonic()))

    def close(self) -> None:
        self.socket.close()
        self._reader.join(5)
