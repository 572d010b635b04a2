"""The autopilot's own parameter metadata: what each parameter means and which values it
takes, so a write outside them is refused before it reaches the vehicle.

PX4 publishes it through MAVLink's component metadata protocol: asked with
MAV_CMD_REQUEST_MESSAGE for COMPONENT_METADATA, it names its general metadata file by a
MAVLink FTP address (``mftp://etc/extras/component_general.json.xz``), whose
``metadataTypes`` entry of type 1 (COMP_METADATA_TYPE_PARAMETER) names the parameter file
(``parameters.json.xz``): every parameter with its ``min``, ``max``, ``values`` (an enum),
``units``, ``shortDesc`` and ``rebootRequired``. The agent reads both files over MAVLink FTP
once the link is up (in the background: about 400 reads of 239 bytes for PX4's file) and
decompresses the xz ones. PX4 itself stores whatever PARAM_SET says (it checks no range),
so this is the only check a write gets. Until the metadata has arrived, and on an autopilot
that does not publish it (ArduPilot, which ships its metadata as apm.pdef files with the
ground station, not on the vehicle), writes go through unchecked and their answers carry no
metadata: the API then says the range was not checked.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import lzma
import math
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from protocol.mavftp import MAX_DATA, FtpError, FtpPayload, Opcode, mftp_path
from protocol.mavlink_extra import MAVLINK_MSG_ID_COMPONENT_METADATA
from protocol.messages import (
    MAX_PARAM_ENUM_VALUES,
    MAX_PARAM_TEXT_CHARS,
    ParamEnumValue,
    ParamMeta,
)
from vehicle_agents.fcu.link import FcuLink
from vehicle_agents.fcu.messages import LinkChange, MavMessage, next_match

log = logging.getLogger(__name__)

COMP_METADATA_TYPE_PARAMETER = 1
MAX_FILE_BYTES = 4 * 1024 * 1024  # PX4's parameters.json.xz is about 100 KB
MAX_JSON_BYTES = 32 * 1024 * 1024  # and about 1.5 MB decompressed


class FtpFailed(Exception):
    pass


class FtpReader:
    """MAVLink FTP's read-only client: open, read in 239-byte pieces, close."""

    def __init__(self, link: FcuLink, reply_s: float = 1.0, attempts: int = 4) -> None:
        self._link = link
        self._reply_s = reply_s
        self._attempts = attempts
        self._seq = 0

    async def read(self, path: str) -> bytes:
        link = self._link
        with link.collect(lambda m: m.get_type() == "FILE_TRANSFER_PROTOCOL") as replies:
            opened = await self._request(replies, Opcode.OPEN_FILE_RO, 0, 0, path.encode())
            if opened.opcode == Opcode.NAK:
                raise FtpFailed(f"{path}: {_nak_reason(opened)}")
            session = opened.session
            size = int.from_bytes(opened.data[:4], "little") if opened.size >= 4 else None
            if size is not None and size > MAX_FILE_BYTES:
                raise FtpFailed(f"{path}: {size} bytes is more than {MAX_FILE_BYTES}")
            content = bytearray()
            try:
                while size is None or len(content) < size:
                    reply = await self._request(
                        replies, Opcode.READ_FILE, session, len(content), b"", MAX_DATA
                    )
                    if reply.opcode == Opcode.NAK:
                        if reply.data[:1] == bytes([FtpError.EOF]):
                            break
                        raise FtpFailed(f"{path}: {_nak_reason(reply)}")
                    if not reply.data or len(content) + len(reply.data) > MAX_FILE_BYTES:
                        break
                    content += reply.data
            finally:
                with contextlib.suppress(FtpFailed, ConnectionError):
                    await self._request(replies, Opcode.TERMINATE_SESSION, session, 0, b"")
        return bytes(content)

    async def _request(
        self,
        replies: asyncio.Queue[MavMessage],
        opcode: Opcode,
        session: int,
        offset: int,
        data: bytes,
        size: int | None = None,
    ) -> FtpPayload:
        link = self._link
        for _ in range(self._attempts):
            self._seq = (self._seq + 1) & 0xFFFF
            seq = self._seq
            request = FtpPayload(
                seq, session, opcode, len(data) if size is None else size, 0, offset, data
            )
            link.send(
                mavlink2.MAVLink_file_transfer_protocol_message(
                    0, link.target_system or 1, link.target_component, request.pack()
                )
            )
            while (message := await next_match(replies, self._reply_s)) is not None:
                reply = FtpPayload.unpack(message.payload)
                # The answer to this request: its seq + 1, naming its opcode.
                if reply.seq == (seq + 1) & 0xFFFF and reply.req_opcode == opcode:
                    return reply
        raise FtpFailed(f"no answer to FTP {opcode.name} after {self._attempts} attempts")


def _nak_reason(reply: FtpPayload) -> str:
    code = reply.data[0] if reply.data else FtpError.FAIL
    try:
        return FtpError(code).name
    except ValueError:
        return f"error {code}"


def _inflate(path: str, data: bytes) -> bytes:
    if path.endswith(".xz"):
        decompressor = lzma.LZMADecompressor()
        data = decompressor.decompress(data, MAX_JSON_BYTES)
        if not decompressor.eof:
            raise FtpFailed(f"{path}: truncated, or more than {MAX_JSON_BYTES} bytes unpacked")
    return data


def _text(value: object) -> str:
    return str(value or "").strip()[:MAX_PARAM_TEXT_CHARS]


def _number(value: object) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) else None


def parse_px4_parameters(document: Any) -> dict[str, ParamMeta]:
    """PX4's parameters.json: {"parameters": [{"name", "min", "max", "values", ...}]}."""
    parsed: dict[str, ParamMeta] = {}
    entries = document.get("parameters", []) if isinstance(document, dict) else []
    for entry in entries if isinstance(entries, list) else []:
        if not isinstance(entry, dict) or not isinstance(entry.get("name"), str):
            continue
        values = None
        if isinstance(entry.get("values"), list):
            values = [
                ParamEnumValue(value=number, description=_text(item.get("description")))
                for item in entry["values"][:MAX_PARAM_ENUM_VALUES]
                if isinstance(item, dict) and (number := _number(item.get("value"))) is not None
            ]
        units = _text(entry.get("units"))[:32] or None
        parsed[entry["name"]] = ParamMeta(
            description=_text(entry.get("shortDesc") or entry.get("longDesc")),
            units=units,
            min=_number(entry.get("min")),
            max=_number(entry.get("max")),
            values=values or None,
            reboot_required=bool(entry.get("rebootRequired", False)),
        )
    return parsed


class ParamMetadata:
    """The vehicle's parameter metadata, read from the autopilot when it publishes it."""

    def __init__(self, link: FcuLink, request_s: float = 2.0, attempts: int = 3) -> None:
        self._link = link
        self._request_s = request_s
        self._attempts = attempts
        self.params: dict[str, ParamMeta] | None = None  # None: none (yet)
        self._wanted = asyncio.Event()
        link.state_listeners.append(self._on_link_change)
        if link.up:
            self._wanted.set()

    def _on_link_change(self, change: LinkChange) -> None:
        if change.up and self.params is None:
            self._wanted.set()

    def of(self, name: str) -> ParamMeta | None:
        return self.params.get(name) if self.params is not None else None

    async def run(self) -> None:
        while True:
            await self._wanted.wait()
            self._wanted.clear()
            try:
                self.params = await self.fetch()
            except (FtpFailed, ValueError, ConnectionError) as error:
                log.warning("parameter metadata not read: %s; writes are not range-checked", error)
                continue
            if self.params is not None:
                log.info("parameter metadata read for %d parameters", len(self.params))

    async def fetch(self) -> dict[str, ParamMeta] | None:
        """None when the autopilot publishes no component metadata."""
        link = self._link
        announced = None
        with link.collect(lambda m: m.get_type() == "COMPONENT_METADATA") as answers:
            for attempt in range(self._attempts):
                link.send_command_long(
                    mavlink2.MAV_CMD_REQUEST_MESSAGE, attempt, [MAVLINK_MSG_ID_COMPONENT_METADATA]
                )
                announced = await next_match(answers, self._request_s)
                if announced is not None:
                    break
        if announced is None:
            log.info("the autopilot publishes no component metadata; writes are not range-checked")
            return None
        general_path = mftp_path(str(announced.uri))
        if general_path is None:
            raise FtpFailed(f"general metadata at {announced.uri!r}, not on the vehicle")
        reader = FtpReader(link)
        general = json.loads(_inflate(general_path, await reader.read(general_path)))
        types = general.get("metadataTypes", []) if isinstance(general, dict) else []
        entry = next(
            (
                item
                for item in types
                if isinstance(item, dict) and item.get("type") == COMP_METADATA_TYPE_PARAMETER
            ),
            None,
        )
        if entry is None:
            raise FtpFailed("the general metadata names no parameter metadata")
        path = mftp_path(str(entry.get("uri", "")))
        if path is None:
            raise FtpFailed(f"parameter metadata at {entry.get('uri')!r}, not on the vehicle")
        return parse_px4_parameters(json.loads(_inflate(path, await reader.read(path))))
