"""The light simulated agents: the real agent protocol over one WebSocket each, a
telemetry frame per 1/R s, numbered, with what the hub acks and how long it took."""

from __future__ import annotations

import asyncio
import contextlib
import secrets
import time
from dataclasses import asdict, dataclass, field
from multiprocessing.synchronize import Event as EventType
from typing import Any

import orjson
import websockets

from protocol.messages import AGENT_WS_PATH, PROTOCOL_VERSION

DRAIN_TIMEOUT_S = 180.0  # after the run, how long the agents wait for their last acks


def vehicle_id(index: int) -> str:
    return f"bench_{index:05d}"


@dataclass
class AgentResult:
    sent: dict[str, int] = field(default_factory=dict)  # frames sent per vehicle
    acked: dict[str, int] = field(default_factory=dict)  # the highest seq acked
    ack_delays_ms: list[float] = field(default_factory=list)
    refused: list[str] = field(default_factory=list)
    last_ack_at: float = 0.0
    late_slots: int = 0  # send slots this process was too busy to keep


def telemetry_frame(seq: int, sent_at: float, index: int) -> bytes:
    """A realistic telemetry frame: what an agent sends about a multirotor in flight."""
    return orjson.dumps(
        {
            "type": "telemetry",
            "seq": seq,
            "time": sent_at,
            "state": {
                "mode": "GUIDED",
                "armed": True,
                "system_status": "ACTIVE",
                "landed_state": "in_air",
                "landed_state_source": "autopilot",
                "lat": 47.39 + index * 1e-4 + seq * 1e-7,
                "lon": 8.54 + seq * 1e-7,
                "alt_msl": 520.0 + seq % 50,
                "alt_rel": 30.0,
                "heading_deg": float(seq % 360),
                "groundspeed": 5.0,
                "climb_rate": 0.1,
                "vn": 3.0,
                "ve": 4.0,
                "roll_deg": 1.5,
                "pitch_deg": -2.0,
                "battery_voltage": 15.9,
                "battery_current": 12.5,
                "battery_remaining": 80.0,
                "gps_fix": 3,
                "satellites": 14,
                "ready_to_fly": True,
                "home_lat": 47.39,
                "home_lon": 8.54,
                "home_alt_msl": 490.0,
                # The sequence number, so that a dashboard can tell which frame it sees.
                "mission_current": seq,
                "mission_total": 10**9,
            },
        }
    )


async def run_agent(
    url: str,
    index: int,
    token: str,
    rate_hz: float,
    duration_s: float,
    welcomed: asyncio.Event,
    start: asyncio.Future[float],
    result: AgentResult,
    compression: str | None,
) -> None:
    vid = vehicle_id(index)
    stream = f"bench-{index}-{secrets.token_hex(4)}"
    hello = {
        "type": "hello",
        "protocol": PROTOCOL_VERSION,
        "vehicle_id": vid,
        "autopilot": "ardupilot",
        "vehicle_type": "multirotor",
        "system_id": 1 + index % 250,
        "modes": ["STABILIZE", "GUIDED", "AUTO", "LOITER", "RTL", "LAND"],
        "capabilities": [],
        "agent_version": "bench",
        "stream_id": stream,
    }
    sent_at: dict[int, float] = {}
    acked = -1
    seq = 0
    done = asyncio.Event()
    async with websockets.connect(
        url,
        additional_headers={"Authorization": f"Bearer {token}"},
        compression=compression,  # type: ignore[arg-type]
        max_queue=None,
        ping_interval=None,
        open_timeout=60,
    ) as websocket:
        await websocket.send(orjson.dumps(hello).decode())
        welcome = orjson.loads(await websocket.recv())
        welcomed.set()
        if welcome.get("type") != "welcome":
            result.refused.append(f"{vid}: {welcome}")
            return
        start_at = await start
        stop_at = start_at + duration_s

        async def receive() -> None:
            nonlocal acked
            async for frame in websocket:
                message = orjson.loads(frame)
                kind = message.get("type")
                if kind == "ack" and message.get("telemetry_seq") is not None:
                    now = time.time()
                    upto = message["telemetry_seq"]
                    for s in range(acked + 1, upto + 1):
                        if (at := sent_at.pop(s, None)) is not None:
                            result.ack_delays_ms.append((now - at) * 1000)
                    acked = max(acked, upto)
                    result.acked[vid] = acked
                    result.last_ack_at = now
                    if seq > 0 and acked >= seq - 1 and time.time() >= stop_at:
                        done.set()
                elif kind == "ping":
                    await websocket.send(
                        orjson.dumps({"type": "pong", "nonce": message["nonce"]}).decode()
                    )
                elif kind == "resend":
                    result.refused.append(f"{vid}: hub asked for a resend {message}")

        receiver = asyncio.create_task(receive())
        period = 1.0 / rate_hz
        # Spread the fleet over the period, as independent vehicles are.
        slot = start_at + period * ((index * 0.618) % 1.0)
        try:
            while slot < stop_at:
                delay = slot - time.time()
                if delay > 0:
                    await asyncio.sleep(delay)
                elif delay < -period:
                    result.late_slots += 1
                now = time.time()
                sent_at[seq] = now
                await websocket.send(telemetry_frame(seq, now, index).decode())
                seq += 1
                slot += period
            result.sent[vid] = seq
            if seq == 0 or acked >= seq - 1:
                done.set()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(done.wait(), DRAIN_TIMEOUT_S)
        finally:
            receiver.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await receiver


def agent_process(
    urls: list[str],
    indices: list[int],
    tokens: dict[int, str],
    rate_hz: float,
    duration_s: float,
    compression: str | None,
    connected: Any,
    go: EventType,
    start_box: Any,
    results: Any,
) -> None:
    async def main() -> None:
        result = AgentResult()
        start: asyncio.Future[float] = asyncio.get_running_loop().create_future()
        welcomed = {index: asyncio.Event() for index in indices}
        tasks = []
        for index in indices:
            url = urls[index % len(urls)].replace("http", "ws", 1) + AGENT_WS_PATH
            tasks.append(
                asyncio.create_task(
                    run_agent(
                        url,
                        index,
                        tokens[index],
                        rate_hz,
                        duration_s,
                        welcomed[index],
                        start,
                        result,
                        compression,
                    )
                )
            )
            await asyncio.sleep(0.002)  # connect as a fleet powers up, not all in one instant
        for event in welcomed.values():
            await event.wait()
        connected.put(len(indices))
        await asyncio.to_thread(go.wait)
        start.set_result(start_box.value)
        await asyncio.gather(*tasks)
        results.put(asdict(result))

    try:
        import uvloop

        uvloop.run(main())
    except ImportError:
        asyncio.run(main())
