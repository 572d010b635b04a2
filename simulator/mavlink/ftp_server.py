"""MAVLink FTP's read-only server (OpenFileRO, ReadFile, TerminateSession, ResetSessions),
serving a few files from memory, as PX4's MavlinkFTP serves its ROMFS: here the component
metadata files the PX4 personality publishes (`px4_metadata`). Anything else is NAKed with
UnknownCommand, as an FTP server answers what it does not implement."""

from __future__ import annotations

from protocol.mavftp import MAX_DATA, FtpError, FtpPayload, Opcode

MAX_SESSIONS = 4  # PX4's MavlinkFTP has one; a few keeps two GCSs from NAKing each other


class FtpServer:
    def __init__(self, files: dict[str, bytes]) -> None:
        self._files = files
        self._sessions: dict[int, bytes] = {}

    def answer(self, request: FtpPayload) -> FtpPayload:
        """The reply to ``request``: its seq + 1, naming its opcode."""
        match request.opcode:
            case Opcode.OPEN_FILE_RO:
                path = request.data.split(b"\x00", 1)[0].decode("utf-8", "replace").lstrip("/")
                content = self._files.get(path)
                if content is None:
                    return self._nak(request, FtpError.FILE_NOT_FOUND)
                free = next((s for s in range(MAX_SESSIONS) if s not in self._sessions), None)
                if free is None:
                    return self._nak(request, FtpError.NO_SESSIONS_AVAILABLE)
                self._sessions[free] = content
                return self._ack(request, len(content).to_bytes(4, "little"), session=free)
            case Opcode.READ_FILE:
                content = self._sessions.get(request.session)
                if content is None:
                    return self._nak(request, FtpError.INVALID_SESSION)
                if request.offset >= len(content):
                    return self._nak(request, FtpError.EOF)
                count = min(request.size or MAX_DATA, MAX_DATA)
                return self._ack(request, content[request.offset : request.offset + count])
            case Opcode.TERMINATE_SESSION:
                if self._sessions.pop(request.session, None) is None:
                    return self._nak(request, FtpError.INVALID_SESSION)
                return self._ack(request, b"")
            case Opcode.RESET_SESSIONS:
                self._sessions.clear()
                return self._ack(request, b"")
            case _:
                return self._nak(request, FtpError.UNKNOWN_COMMAND)

    @staticmethod
    def _ack(request: FtpPayload, data: bytes, session: int | None = None) -> FtpPayload:
        return FtpPayload(
            request.seq + 1,
            request.session if session is None else session,
            Opcode.ACK,
            len(data),
            request.opcode,
            request.offset,
            data,
        )

    @staticmethod
    def _nak(request: FtpPayload, error: FtpError) -> FtpPayload:
        return FtpPayload(
            request.seq + 1, request.session, Opcode.NAK, 1, request.opcode, 0, bytes([error])
        )
