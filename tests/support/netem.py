"""A poor field link made real: a Linux network namespace joined to this one by a veth
pair whose both directions are shaped in the kernel. Processes started with
`FieldLink.command` run inside the namespace and reach this side only across the shaped
link; everything else on the machine is untouched.

The shaping is `tc netem` (delay with jitter, loss, reordering, a rate cap) where the
kernel has it. Some kernels are built without it (sch_netem; a Firecracker guest, for
one, answers "Specified qdisc kind is unknown"): then the rate cap is still the kernel's
(`tbf`, which also drops what waits too long), and `ImpairedRelay`, a TCP relay on this
side of the pair, adds the delay, the jitter and the loss as TCP shows them to the
programs on either end (a lost segment stalls the byte stream for a retransmission
timeout; reordering is hidden by TCP altogether). `FieldLink.netem` says which it is.

Needs root (or CAP_NET_ADMIN) and iproute2; where a namespace cannot be made the test
is skipped, saying why.
"""

from __future__ import annotations

import contextlib
import heapq
import random
import secrets
import socket
import subprocess
import threading
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import pytest

from tests.support.tcp_proxy import CuttableProxy, Filter

# A poor cellular or long-range radio link, as issue 24 states it.
DELAY_S, JITTER_S, LOSS, RATE = 0.300, 0.050, 0.05, "256kbit"
FIELD_NETEM = (
    *("delay", f"{DELAY_S * 1000:.0f}ms", f"{JITTER_S * 1000:.0f}ms"),
    *("loss", f"{LOSS * 100:g}%", "reorder", "1%", "rate", RATE),
)
# Without netem: the rate cap alone, queueing at most this long before tail drops.
FIELD_TBF = ("rate", RATE, "burst", "4kb", "latency", "400ms")
# Linux's smallest retransmission timeout plus a round trip: what one lost segment costs.
RETRANSMIT_S = 0.2 + 2 * DELAY_S


@dataclass(frozen=True)
class FieldLink:
    namespace: str
    host_address: str  # this side of the veth pair
    field_address: str  # the namespace's side
    netem: bool  # shaped by netem; False: tbf, and the relay must add delay and loss

    def command(self, argv: Sequence[str]) -> list[str]:
        """``argv`` run inside the namespace (`ip netns exec` execs it: same pid)."""
        return ["ip", "netns", "exec", self.namespace, *argv]


def _run(*argv: str) -> None:
    subprocess.run(list(argv), check=True, capture_output=True, timeout=10)


def _shape(namespace: str, host_if: str, field_if: str) -> bool:
    """Shape both directions (a qdisc shapes what leaves its interface); True for netem."""
    sides = ((host_if, ()), (field_if, ("-n", namespace)))
    try:
        for device, where in sides:
            _run("tc", *where, "qdisc", "add", "dev", device, "root", "netem", *FIELD_NETEM)
        return True
    except subprocess.CalledProcessError as error:
        if b"unknown" not in error.stderr:
            raise
    for device, where in sides:
        _run("tc", *where, "qdisc", "add", "dev", device, "root", "tbf", *FIELD_TBF)
    return False


@contextlib.contextmanager
def field_link() -> Iterator[FieldLink]:
    """A fresh namespace and veth pair shaped both ways; all removed after."""
    tag = secrets.token_hex(3)
    namespace = f"gcsfield{tag}"
    host_if, field_if = f"vgh{tag}", f"vgf{tag}"  # interface names: at most 15 characters
    # A /30 in 10.213.0.0/16 picked at random, so parallel runs do not share one.
    block = secrets.randbelow(16384) * 4
    prefix = f"10.213.{block // 256}."
    host_address, field_address = f"{prefix}{block % 256 + 1}", f"{prefix}{block % 256 + 2}"
    try:
        _run("ip", "netns", "add", namespace)
    except (OSError, subprocess.CalledProcessError) as error:
        stderr = getattr(error, "stderr", b"") or b""
        pytest.skip(f"cannot make a network namespace (`ip netns add`): {error} {stderr!r}")
    try:
        _run("ip", "link", "add", host_if, "type", "veth", "peer", "name", field_if)
        _run("ip", "link", "set", field_if, "netns", namespace)
        _run("ip", "addr", "add", f"{host_address}/30", "dev", host_if)
        _run("ip", "link", "set", host_if, "up")
        _run("ip", "-n", namespace, "addr", "add", f"{field_address}/30", "dev", field_if)
        _run("ip", "-n", namespace, "link", "set", field_if, "up")
        _run("ip", "-n", namespace, "link", "set", "lo", "up")
        netem = _shape(namespace, host_if, field_if)
        yield FieldLink(namespace, host_address, field_address, netem)
    finally:
        # Deleting the namespace deletes its end of the pair, and with it the other.
        with contextlib.suppress(subprocess.CalledProcessError):
            _run("ip", "netns", "del", namespace)
        with contextlib.suppress(subprocess.CalledProcessError):
            _run("ip", "link", "del", host_if)


class ImpairedRelay(CuttableProxy):
    """A TCP relay listening on ``listen_host`` that hands each chunk on after the link's
    delay and jitter, in order (TCP delivers in order), and, with the link's loss
    probability, only after a retransmission stall that holds back everything behind it.
    With ``impaired=False`` it only relays (netem does the rest)."""

    def __init__(
        self, listen_host: str, target: tuple[str, int], impaired: bool, seed: int = 24
    ) -> None:
        super().__init__(target)
        self.listen_host = listen_host
        self.impaired = impaired
        self._random = random.Random(seed)
        self._random_lock = threading.Lock()

    def start(self) -> None:
        listener = socket.create_server((self.listen_host, self.port))
        self._listener = listener
        threading.Thread(target=self._accept, args=(listener,), daemon=True).start()

    def _delay(self) -> float:
        with self._random_lock:
            delay = DELAY_S + self._random.uniform(-JITTER_S, JITTER_S)
            if self._random.random() < LOSS:
                delay += RETRANSMIT_S
        return delay

    def _pump(self, source: socket.socket, sink: socket.socket, forward: Filter) -> None:  # type: ignore[override]
        if not self.impaired:
            CuttableProxy._pump(source, sink, forward)
            return
        due: list[tuple[float, int, bytes]] = []
        ready = threading.Condition()
        order = 0
        closed = False

        def deliver() -> None:
            try:
                while True:
                    with ready:
                        while not due and not closed:
                            ready.wait()
                        if not due:
                            return
                        at, _, data = due[0]
                        wait = at - time.monotonic()
                        if wait > 0:
                            ready.wait(wait)  # the chunk is still on its way
                            continue
                        heapq.heappop(due)
                    sink.sendall(data)
            except OSError:
                pass
            finally:
                with contextlib.suppress(OSError):
                    sink.shutdown(socket.SHUT_RDWR)

        threading.Thread(target=deliver, daemon=True).start()
        last = 0.0
        try:
            while data := source.recv(65536):
                # In order: a chunk never overtakes the one before it.
                last = max(last, time.monotonic() + self._delay())
                with ready:
                    order += 1
                    heapq.heappush(due, (last, order, forward(data)))
                    ready.notify()
        except OSError:
            pass
        finally:
            with ready:
                closed = True
                ready.notify()
