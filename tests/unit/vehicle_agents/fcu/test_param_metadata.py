"""Parameter metadata: MAVLink FTP's payload and the simulator's server, PX4's parameter
JSON and ArduPilot's apm.pdef.json read into the same ParamMeta, and the check."""

from __future__ import annotations

import json
import lzma
from pathlib import Path

from backend.fleet.param_catalog import ParamCatalog
from protocol.mavftp import MAX_DATA, FtpError, FtpPayload, Opcode, mftp_path
from protocol.messages import ParamMeta
from protocol.param_checks import out_of_range
from simulator.mavlink.ftp_server import FtpServer
from simulator.params.px4 import PARAMETERS_PATH, metadata_files
from vehicle_agents.fcu.param_metadata import parse_px4_parameters

METADATA = Path(__file__).parents[3] / "data" / "param_metadata"


def test_mftp_addresses_and_the_payload_round_trip() -> None:
    assert mftp_path("mftp://etc/extras/component_general.json.xz") == (
        "etc/extras/component_general.json.xz"
    )
    assert mftp_path("mftp://[;comp=1]etc/x.json") == "etc/x.json"
    assert mftp_path("https://px4-travis.s3.amazonaws.com/x.json.xz") is None
    payload = FtpPayload(65535, 2, Opcode.READ_FILE, 7, 0, 239 * 3, b"abcdefg")
    packed = payload.pack()
    assert len(packed) == 251
    assert FtpPayload.unpack(packed) == payload


def test_the_simulators_ftp_serves_px4s_metadata_in_pieces_then_eof() -> None:
    files = metadata_files()
    server = FtpServer(files)
    opened = server.answer(
        FtpPayload(10, 0, Opcode.OPEN_FILE_RO, 0, 0, 0, PARAMETERS_PATH.encode())
    )
    assert (opened.opcode, opened.seq, opened.req_opcode) == (Opcode.ACK, 11, Opcode.OPEN_FILE_RO)
    size = int.from_bytes(opened.data, "little")
    content = b""
    while True:
        reply = server.answer(
            FtpPayload(12, opened.session, Opcode.READ_FILE, MAX_DATA, 0, len(content), b"")
        )
        if reply.opcode == Opcode.NAK:
            assert reply.data == bytes([FtpError.EOF])
            break
        content += reply.data
    assert len(content) == size
    parsed = parse_px4_parameters(json.loads(lzma.decompress(content)))
    meta = parsed["COM_RC_IN_MODE"]
    assert [v.value for v in meta.values or []] == [0, 1, 2, 3, 4]
    assert out_of_range("COM_RC_IN_MODE", 3, meta) is None
    assert "9 is not one of the values it takes" in (out_of_range("COM_RC_IN_MODE", 9, meta) or "")
    missing = server.answer(FtpPayload(1, 0, Opcode.OPEN_FILE_RO, 0, 0, 0, b"etc/nothing"))
    assert (missing.opcode, missing.data) == (Opcode.NAK, bytes([FtpError.FILE_NOT_FOUND]))


def test_a_range_open_at_one_end_and_no_metadata_at_all() -> None:
    assert out_of_range("X", -1, ParamMeta(min=0)) == "X: -1 is outside its range 0.."
    assert out_of_range("X", 1e9, ParamMeta(min=0)) is None
    assert out_of_range("X", 1e9, ParamMeta()) is None


def test_arducopters_file_is_read_once_and_only_for_ardupilot() -> None:
    catalog = ParamCatalog(METADATA)
    speed = catalog.meta("ardupilot", "multirotor", "WPNAV_SPEED")
    assert speed is not None
    assert (speed.min, speed.max, speed.units, speed.source) == (10, 2000, "cm/s", "file")
    assert catalog.meta("px4", "multirotor", "WPNAV_SPEED") is None  # PX4 serves its own
    assert catalog.for_vehicle("ardupilot", "fixed_wing") is None  # no ArduPlane file here
    assert ParamCatalog(None).for_vehicle("ardupilot", "multirotor") is None
