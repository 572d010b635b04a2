"""The agent's last log line says it stopped and why: a signal, an error, or the end."""

from __future__ import annotations

import asyncio
import logging
import os
import signal

import pytest

from vehicle_agents.cli import run_until_signalled


async def _terminated() -> None:
    os.kill(os.getpid(), signal.SIGTERM)  # as systemd stops the service
    await asyncio.Event().wait()


async def _broken() -> None:
    raise ConnectionRefusedError("tcp:127.0.0.1:5760 refused the connection")


async def _done() -> None:
    return None


def test_a_signal_is_named_in_the_last_line(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.INFO, logger="gcs.agent"):
        assert run_until_signalled(_terminated()) == 0
    assert caplog.messages[-2:] == [
        "agent: SIGTERM received, stopping",
        "agent stopped: on SIGTERM",
    ]


def test_an_error_is_named_in_the_last_line(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.INFO, logger="gcs.agent"):
        assert run_until_signalled(_broken()) == 1
    last = caplog.records[-1]
    assert last.levelno == logging.CRITICAL
    assert last.getMessage() == (
        "agent stopped: ConnectionRefusedError: tcp:127.0.0.1:5760 refused the connection"
    )


def test_an_end_is_named_too(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.INFO, logger="gcs.agent"):
        assert run_until_signalled(_done()) == 0
    assert caplog.messages[-1] == "agent stopped: its work ended"
