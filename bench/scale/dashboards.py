"""The dashboards: live-feed clients that time each vehicle state and check its order."""

from __future__ import annotations

import asyncio
import time
from array import array
from dataclasses import asdict, dataclass, field
from multiprocessing.synchronize import Event as EventType
from typing import Any

import orjson
import websockets

from protocol.messages import CLIENT_WS_PATH


@dataclass
class DashboardResult:
    frames: int = 0
    updates: int = 0
    delays_ms: list[float] = field(default_factory=list)
    regressions: int = 0  # a state older than one already shown
    repeats: int = 0  # the same state twice
    last_seq: dict[str, int] = field(default_factory=dict)
    closed: list[str] = field(default_factory=list)
    bytes_in: int = 0


async def run_dashboard(
    url: str, token: str, result: DashboardResult, stop: asyncio.Event, connected: asyncio.Event
) -> None:
    delays = array("d")
    last = result.last_seq
    links: dict[str, bool | None] = {}
    async with websockets.connect(
        url,
        additional_headers={"Authorization": f"Bearer {token}"},
        max_queue=None,
        max_size=None,
        open_timeout=60,
    ) as websocket:
        connected.set()

        def vehicle(change: dict[str, Any], now: float) -> None:
            vid = change["id"]
            if not vid.startswith("bench_"):
                return
            state = change.get("state") or {}
            seq = state.get("mission_current")
            if seq is None:
                return
            result.updates += 1
            previous = last.get(vid, -1)
            connected = change.get("connected")
            if seq < previous:
                result.regressions += 1
            elif seq == previous:
                # The same state again is a duplicate, unless the link changed (an agent
                # that leaves keeps its last state, now offline).
                result.repeats += links.get(vid) == connected
                links[vid] = connected
            else:
                links[vid] = connected
                last[vid] = seq
                if change.get("last_seen") is not None:
                    delays.append((now - change["last_seen"]) * 1000)

        while not stop.is_set():
            try:
                frame = await asyncio.wait_for(websocket.recv(), 0.5)
            except TimeoutError:
                continue
            except websockets.ConnectionClosed as closed:
                result.closed.append(f"{closed.rcvd}")
                break
            now = time.time()
            result.frames += 1
            result.bytes_in += len(frame)
            message = orjson.loads(frame)
            kind = message.get("type")
            if kind == "vehicles":
                for change in message["vehicles"]:
                    vehicle(change, now)
            elif kind == "vehicle":  # a hub from before batching
                vehicle(message["vehicle"], now)
            elif kind == "fleet":
                for summary in message["vehicles"]:
                    state = summary.get("state") or {}
                    if summary["id"].startswith("bench_") and state.get("mission_current"):
                        last[summary["id"]] = max(
                            last.get(summary["id"], -1), state["mission_current"]
                        )
    result.delays_ms = delays.tolist()


def dashboard_process(
    urls: list[str], token: str, count: int, connected: Any, stop_flag: EventType, results: Any
) -> None:
    async def main() -> None:
        stop = asyncio.Event()
        outcomes = [DashboardResult() for _ in range(count)]
        ready = [asyncio.Event() for _ in range(count)]
        tasks = [
            asyncio.create_task(
                run_dashboard(
                    urls[i % len(urls)].replace("http", "ws", 1) + CLIENT_WS_PATH,
                    token,
                    outcomes[i],
                    stop,
                    ready[i],
                )
            )
            for i in range(count)
        ]
        for event in ready:
            await event.wait()
        connected.put(count)
        await asyncio.to_thread(stop_flag.wait)
        stop.set()
        await asyncio.gather(*tasks)
        results.put([asdict(outcome) for outcome in outcomes])

    try:
        import uvloop

        uvloop.run(main())
    except ImportError:
        asyncio.run(main())
