"""MAVLink FTP's payload (https://mavlink.io/en/services/ftp.html): the 251 bytes a
FILE_TRANSFER_PROTOCOL message carries, for the read-only subset the component metadata
protocol needs (OpenFileRO, ReadFile, TerminateSession). The agent reads files with it and
the simulator serves them with it, so both speak the same layout.

Standard library only, as the rest of the protocol package.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from enum import IntEnum

PAYLOAD_LEN = 251
HEADER = struct.Struct("<HBBBBBBI")  # seq, session, opcode, size, req_opcode, burst, pad, offset
MAX_DATA = PAYLOAD_LEN - HEADER.size  # 239


class Opcode(IntEnum):
    NONE = 0
    TERMINATE_SESSION = 1
    RESET_SESSIONS = 2
    OPEN_FILE_RO = 4
    READ_FILE = 5
    ACK = 128
    NAK = 129


class FtpError(IntEnum):
    """A NAK's first data byte."""

    NONE = 0
    FAIL = 1
    FAIL_ERRNO = 2
    INVALID_DATA_SIZE = 3
    INVALID_SESSION = 4
    NO_SESSIONS_AVAILABLE = 5
    EOF = 6
    UNKNOWN_COMMAND = 7
    FILE_EXISTS = 8
    FILE_PROTECTED = 9
    FILE_NOT_FOUND = 10


@dataclass(frozen=True)
class FtpPayload:
    seq: int
    session: int
    opcode: int
    size: int
    req_opcode: int
    offset: int
    data: bytes

    def pack(self) -> list[int]:
        """As FILE_TRANSFER_PROTOCOL.payload (a list of 251 bytes)."""
        head = HEADER.pack(
            self.seq & 0xFFFF,
            self.session,
            self.opcode,
            self.size,
            self.req_opcode,
            0,
            0,
            self.offset,
        )
        body = self.data[:MAX_DATA]
        return list(head + body + bytes(MAX_DATA - len(body)))

    @classmethod
    def unpack(cls, payload: bytes | list[int]) -> FtpPayload:
        raw = bytes(payload)[:PAYLOAD_LEN].ljust(PAYLOAD_LEN, b"\x00")
        seq, session, opcode, size, req_opcode, _burst, _pad, offset = HEADER.unpack_from(raw)
        size = min(size, MAX_DATA)
        return cls(
            seq, session, opcode, size, req_opcode, offset, raw[HEADER.size : HEADER.size + size]
        )


def mftp_path(uri: str) -> str | None:
    """The FTP path of an ``mftp://`` URI (PX4's "mftp://etc/extras/x.json.xz" is
    "etc/extras/x.json.xz"; an optional "[;comp=N]" names another component); None for
    any other scheme (an http:// fallback the agent does not fetch)."""
    prefix = "mftp://"
    if not uri.startswith(prefix):
        return None
    path = uri[len(prefix) :]
    if path.startswith("[") and "]" in path:
        path = path[path.index("]") + 1 :]
    return path or None
