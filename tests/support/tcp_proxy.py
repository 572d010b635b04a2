"""A TCP proxy on loopback that a test can cut and restore, to make a real server
'briefly unavailable' without stopping it.

A subclass can also see and change the bytes going through: `filters()` gives, for each
new connection, what to do with a chunk in either direction (pass it, record it, drop
it, inject more).
"""

from __future__ import annotations

import contextlib
import socket
import threading
from collections.abc import Callable
from typing import Self

Filter = Callable[[bytes], bytes]
"""What to send on for a chunk read from one side: the chunk itself, more, or nothing."""


def _unchanged(data: bytes) -> bytes:
    return data


class CuttableProxy:
    def __init__(self, target: tuple[str, int]) -> None:
        self.target = target
        probe = socket.create_server(("127.0.0.1", 0))
        self.port = probe.getsockname()[1]
        probe.close()
        self._sockets: list[socket.socket] = []
        self._lock = threading.Lock()
        self._listener: socket.socket | None = None

    def __enter__(self) -> Self:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.cut()

    def start(self) -> None:
        """Listen (again) on the same port."""
        listener = socket.create_server(("127.0.0.1", self.port), reuse_port=False)
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._listener = listener
        threading.Thread(target=self._accept, args=(listener,), daemon=True).start()

    def cut(self) -> None:
        """Refuse new connections and drop the open ones, as a failed host or an unplugged
        cable would."""
        with self._lock:
            listener, self._listener = self._listener, None
            sockets, self._sockets = self._sockets, []
        for each in [listener, *sockets]:
            if each is not None:
                with contextlib.suppress(OSError):
                    each.shutdown(socket.SHUT_RDWR)
                each.close()

    def filters(self) -> tuple[Filter, Filter]:
        """For a new connection: the filter for client to target, then target to client.
        Called once per connection, so a filter may keep state (a parser, a count)."""
        return _unchanged, _unchanged

    def _accept(self, listener: socket.socket) -> None:
        while True:
            try:
                client, _ = listener.accept()
            except OSError:
                return  # cut
            try:
                upstream = socket.create_connection(self.target)
            except OSError:
                client.close()  # the target is down: so is this connection
                continue
            with self._lock:
                self._sockets += [client, upstream]
            to_target, to_client = self.filters()
            for source, sink, each in (
                (client, upstream, to_target),
                (upstream, client, to_client),
            ):
                threading.Thread(target=self._pump, args=(source, sink, each), daemon=True).start()

    @staticmethod
    def _pump(source: socket.socket, sink: socket.socket, forward: Filter) -> None:
        try:
            while data := source.recv(65536):
                if out := forward(data):
                    sink.sendall(out)
        except OSError:
            pass
        finally:
            for each in (source, sink):
                with contextlib.suppress(OSError):
                    each.shutdown(socket.SHUT_RDWR)
