"""The agent's onboard telemetry log: one .tlog per flight, uploaded after landing.

:class:`TlogRecorder` takes every MAVLink message the flight controller sends and,
from arming to disarming, writes it in the format QGroundControl and MAVProxy use:
an 8-byte big-endian count of microseconds since the Unix epoch, then the packet
exactly as it arrived. Finished files are queued in ``finished`` for
:func:`upload_tlog`.

Only the standard library and pymavlink's dialect constants are used, so this runs
on the smallest companion computers.
"""

from __future__ import annotations

import collections
import contextlib
import logging
import os
import re
import struct
import urllib.parse
from datetime import UTC, datetime
from pathlib import Path
from typing import IO, Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from vehicle_agents.fcu.modes import is_armed
from vehicle_agents.hub.http import HttpError, send

log = logging.getLogger(__name__)

DEFAULT_MAX_BYTES = 200 * 1024 * 1024
WRITE_BUFFER_BYTES = 64 * 1024

_RECORD_TIME = struct.Struct(">Q")
_UNSAFE_FILENAME_CHARACTERS = re.compile(r"[^A-Za-z0-9_.-]")


class TlogRecorder:
    """Records one .tlog per flight (arm to disarm) into ``directory``.

    Arming and disarming are read from the HEARTBEATs of the first autopilot heard
    (the first HEARTBEAT whose autopilot is not MAV_AUTOPILOT_INVALID); heartbeats
    from GCSs, cameras or gimbals on the same link are recorded but never start or
    end a flight. A flight starts on an armed heartbeat while no file is open; that
    includes the very first heartbeat, so an agent restarted in the air still logs
    the rest of the flight. The arming and disarming heartbeats are in the file.

    The recorder is not thread-safe: call it from one thread (the one that handles
    received messages). Writes go through a 64 KiB buffer; a crash loses at most
    that much. A flight that would grow past ``max_bytes`` stops being written
    (logged once) but the file is still finished normally on disarm. If the disk
    fails, the rest of that flight is not recorded: the error is logged once, the
    file is left out of ``finished``, and the next arming starts a new file.
    """

    def __init__(
        self, directory: Path, vehicle_id: str, max_bytes: int = DEFAULT_MAX_BYTES
    ) -> None:
        self.directory = directory
        self.vehicle_id = vehicle_id
        self.max_bytes = max_bytes
        self.finished: collections.deque[Path] = collections.deque()
        self._autopilot: tuple[int, int] | None = None  # (system, component)
        self._file: IO[bytes] | None = None
        self._path: Path | None = None
        self._bytes = 0
        self._full = False
        self._in_flight = False
        self._last_usec = 0

    @property
    def recording(self) -> Path | None:
        """The file of the flight in progress, if one is."""
        return self._path

    def record(self, message: Any, received_at: float) -> None:
        """Handle one received message; ``received_at`` is its unix time (``time.time()``)."""
        if message.get_type() == "BAD_DATA":
            return
        armed = self._autopilot_armed(message)
        if armed and not self._in_flight:
            self._in_flight = True
            self._open(received_at)
        if self._file is not None:
            self._write(message, received_at)
        if armed is False and self._in_flight:
            self._in_flight = False
            if self._file is not None:
                self._finish()

    def close(self) -> None:
        """Flush and close the flight in progress, which is then queued in ``finished``."""
        self._in_flight = False
        if self._file is not None:
            self._finish()

    # -- internals ----------------------------------------------------------

    def _autopilot_armed(self, message: Any) -> bool | None:
        """For a HEARTBEAT from the autopilot, whether it is armed; None for anything else."""
        if message.get_type() != "HEARTBEAT":
            return None
        source = (message.get_srcSystem(), message.get_srcComponent())
        if self._autopilot is None and message.autopilot != mavlink2.MAV_AUTOPILOT_INVALID:
            self._autopilot = source
        if source != self._autopilot:
            return None
        return is_armed(message)

    def _open(self, received_at: float) -> None:
        stamp = datetime.fromtimestamp(received_at, UTC).strftime("%Y%m%dT%H%M%S")
        stem = f"{_UNSAFE_FILENAME_CHARACTERS.sub('_', self.vehicle_id)}_{stamp}"
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
            path = self.directory / f"{stem}.tlog"
            duplicate = 0
            while True:
                try:
                    self._file = path.open("xb", buffering=WRITE_BUFFER_BYTES)
                    break
                except FileExistsError:  # armed twice within a second
                    duplicate += 1
                    path = self.directory / f"{stem}_{duplicate}.tlog"
        except OSError as error:
            log.error("cannot start onboard tlog in %s: %s", self.directory, error)
            return
        self._path = path
        self._bytes = 0
        self._full = False
        log.info("recording onboard tlog %s", path)

    def _write(self, message: Any, received_at: float) -> None:
        assert self._file is not None
        packet = message.get_msgbuf()
        if not packet:
            return  # built locally and never packed: nothing was received
        usec = max(self._last_usec, round(received_at * 1e6))  # the wall clock may step back
        self._last_usec = usec
        size = _RECORD_TIME.size + len(packet)
        if self._bytes + size > self.max_bytes:
            if not self._full:
                log.warning("onboard tlog %s reached %d bytes: stopped", self._path, self._bytes)
                self._full = True
            return
        try:
            self._file.write(_RECORD_TIME.pack(usec))
            self._file.write(packet)
        except OSError as error:
            self._abandon(error)
            return
        self._bytes += size

    def _finish(self) -> None:
        assert self._file is not None
        assert self._path is not None
        try:
            self._file.close()
        except OSError as error:
            self._abandon(error)
            return
        log.info("onboard tlog %s finished: %d bytes", self._path, self._bytes)
        self.finished.append(self._path)
        self._file = self._path = None

    def _abandon(self, error: OSError) -> None:
        log.error("onboard tlog %s lost: %s", self._path, error)
        if self._file is not None:
            with contextlib.suppress(OSError):  # already failing; the first error was logged
                self._file.close()
        self._file = self._path = None


class TlogUploadError(Exception):
    """The hub answered an upload with something other than 2xx."""

    def __init__(self, path: Path, status: int, reason: str, body: str) -> None:
        super().__init__(f"uploading {path.name} failed: HTTP {status} {reason}: {body}")
        self.status = status


def upload_tlog(path: Path, url: str, token: str, timeout_s: float = 60) -> None:
    """POST the file at ``path`` to ``url``, streamed from disk.

    The hub's endpoint is ``POST {hub_http_base}/api/v1/vehicles/{vehicle_id}/tlogs``.
    Headers: ``Content-Type: application/octet-stream``, ``Authorization: Bearer``,
    ``Content-Length`` and ``X-Filename`` (the file name, percent-encoded; names the
    recorder makes need no encoding). A non-2xx answer (redirects included) raises
    :class:`TlogUploadError`; network failures raise ``OSError`` (``URLError``).
    """
    if urllib.parse.urlsplit(url).scheme not in ("http", "https"):
        raise ValueError(f"tlog upload URL must be http(s): {url!r}")
    with path.open("rb") as file:
        size = os.fstat(file.fileno()).st_size
        try:
            send(
                "POST",
                url,
                token=token,
                body=file,
                headers={
                    "Content-Type": "application/octet-stream",
                    "Content-Length": str(size),
                    "X-Filename": urllib.parse.quote(path.name, safe=""),
                },
                timeout_s=timeout_s,
            )
        except HttpError as error:
            raise TlogUploadError(path, error.status, error.reason, error.body) from None
