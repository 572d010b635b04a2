"""``python -m simulator.health tcp:HOST:PORT``: is a simulator there, sending HEARTBEATs?

The simulator image's health check. It connects as a MAVLink client would and waits for
one HEARTBEAT, so a simulator that listens but no longer ticks is unhealthy too. Exit 0
when one came, 1 otherwise (with the reason), 2 on a bad address.
"""

from __future__ import annotations

import socket
import sys
import time
from collections.abc import Sequence
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from simulator.config import ListenAddress

TIMEOUT_S = 4.0  # the simulator sends a HEARTBEAT every second


def heartbeat_from(address: ListenAddress, timeout_s: float = TIMEOUT_S) -> str | None:
    """None when a HEARTBEAT arrives within ``timeout_s``, else what went wrong."""
    if address.scheme != "tcp":
        return f"{address}: only a tcp: simulator can be asked (udp has no connection)"
    host = "127.0.0.1" if address.host in ("0.0.0.0", "") else address.host
    parser: Any = mavlink2.MAVLink(None)
    parser.robust_parsing = True
    deadline = time.monotonic() + timeout_s
    try:
        with socket.create_connection((host, address.port), timeout=timeout_s) as connection:
            while (left := deadline - time.monotonic()) > 0:
                connection.settimeout(left)
                data = connection.recv(4096)
                if not data:
                    return f"{address} closed the connection before a HEARTBEAT"
                for message in parser.parse_buffer(data) or []:
                    if message.get_type() == "HEARTBEAT":
                        return None
    except TimeoutError:
        pass
    except OSError as error:
        return f"{address}: {error}"
    return f"no HEARTBEAT from {address} within {timeout_s:g} s"


def main(argv: Sequence[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    if len(args) != 1:
        print("usage: python -m simulator.health tcp:HOST:PORT", file=sys.stderr)
        return 2
    try:
        address = ListenAddress.parse(args[0])
    except ValueError as error:
        print(f"simulator.health: {error}", file=sys.stderr)
        return 2
    problem = heartbeat_from(address)
    if problem is not None:
        print(f"simulator.health: unhealthy: {problem}", file=sys.stderr)
        return 1
    print(f"healthy: {address} sends HEARTBEATs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
