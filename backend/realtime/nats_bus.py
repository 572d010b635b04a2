"""The bus of several hubs: each hub's own bus, joined by core NATS subjects.

A hub publishes to its in-process bus as always (its own dashboards, writer and 3D
view see the message at once, with the same delivery rules), and the topics that other
hubs' dashboards need go on to NATS as well: ``<prefix>.bus.<topic>``. Each hub takes
those subjects and publishes what the *other* hubs sent to its own bus (the connection
is ``no_echo``, so a hub never hears itself twice).

What crosses and what stays:
- ``vehicle.state``, ``vehicle.event``: cross. A dashboard on any hub sees every vehicle.
- ``storage``: stays. The hub that holds an agent's connection writes its frames to the
  shared PostgreSQL, and acknowledges them to the agent only once committed: the agent's
  outbox is the durable copy until then.
- ``scans``, ``surveys``, ``map``: stay for now. Each hub builds its point map and its
  surveys' progress from what it stores and sees; a scan subscriber sees the scans of
  the vehicles connected to its own hub.

Core NATS, not JetStream, on purpose: every message here is live state that the next
one replaces (at most once is the right promise, and a replay of stale positions after
a reconnect would be wrong). Durability lives where it already is: the agent's outbox
(replayed until the database has the frame) and the database (history, leases). A
JetStream stream would be a second durable copy that no reader needs.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable, Hashable
from dataclasses import dataclass
from typing import Any

from nats.aio.client import Client as Nats
from nats.aio.msg import Msg
from pydantic import BaseModel

from backend.realtime.bus import InProcessBus, Subscription, Topic
from protocol.messages import LiveEvent, VehicleSummary

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SharedTopic:
    """How one topic's messages travel between hubs: to bytes and back, with their key."""

    encode: Callable[[Hashable, Any], bytes]
    decode: Callable[[bytes], tuple[Hashable, Any]]


def _model(kind: type[BaseModel], key_of: Callable[[Any], Hashable]) -> SharedTopic:
    def decode(data: bytes) -> tuple[Hashable, Any]:
        message = kind.model_validate_json(data)
        return key_of(message), message

    return SharedTopic(lambda _key, message: message.model_dump_json().encode(), decode)


SHARED: dict[Topic, SharedTopic] = {
    Topic.VEHICLE_STATE: _model(VehicleSummary, lambda summary: summary.id),
    Topic.VEHICLE_EVENT: _model(LiveEvent, lambda event: event.vehicle_id),
}

RemoteListener = Callable[[Topic, Any], Awaitable[None]]


class NatsBus:
    """The ``Bus`` of one hub among several (see the module's note)."""

    def __init__(self, nats: Nats, prefix: str) -> None:
        self._nats = nats
        self._prefix = prefix
        self._local = InProcessBus()
        # Told of each message from another hub before its subscribers are: the hub's
        # registry mirrors remote vehicles, so commands and leases can find them.
        self.on_remote: RemoteListener | None = None
        self.received = 0  # messages from other hubs
        self.undecodable = 0

    def subject(self, topic: Topic) -> str:
        return f"{self._prefix}.bus.{topic.value}"

    def subscribe(self, topic: Topic, subscription: Subscription) -> None:
        self._local.subscribe(topic, subscription)

    def unsubscribe(self, topic: Topic, subscription: Subscription) -> None:
        self._local.unsubscribe(topic, subscription)

    def subscribers(self, topic: Topic) -> int:
        # Other hubs' readers count too: what crosses is always built.
        return self._local.subscribers(topic) + (1 if topic in SHARED else 0)

    async def publish(self, topic: Topic, key: Hashable, message: Any) -> None:
        await self._local.publish(topic, key, message)
        shared = SHARED.get(topic)
        if shared is not None and self._nats.is_connected:
            # Buffered by the client and flushed by its own task: no round trip here.
            # While NATS is away the other hubs miss live state, which the next message
            # replaces; nothing stored depends on it.
            await self._nats.publish(self.subject(topic), shared.encode(key, message))

    async def publish_here(self, topic: Topic, key: Hashable, message: Any) -> None:
        """To this hub's own subscribers only: what this hub concluded of another's
        vehicle is not that hub's word to repeat."""
        await self._local.publish(topic, key, message)

    async def run(self) -> None:
        """Take the other hubs' messages until cancelled."""
        subscriptions = []
        try:
            for topic in SHARED:
                subscriptions.append(
                    await self._nats.subscribe(self.subject(topic), cb=self._receiver(topic))
                )
            await asyncio.Event().wait()  # the callbacks do the work
        finally:
            for subscription in subscriptions:
                try:
                    await subscription.unsubscribe()
                except Exception as error:
                    # The connection is closing with the hub; nothing left to undo.
                    log.debug("bus unsubscribe: %r", error)

    def _receiver(self, topic: Topic) -> Callable[[Msg], Any]:
        shared = SHARED[topic]

        async def receive(msg: Msg) -> None:
            try:
                key, message = shared.decode(msg.data)
            except (ValueError, IndexError) as error:
                self.undecodable += 1
                log.warning("undecodable %s message from another hub: %s", topic.value, error)
                return
            self.received += 1
            if self.on_remote is not None:
                await self.on_remote(topic, message)
            await self._local.publish(topic, key, message)

        return receive
