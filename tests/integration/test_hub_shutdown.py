"""A hub told to stop stops within its grace, whatever requests are in progress: uvicorn
otherwise waits for each to end (a survey plan, an export, a body still arriving)."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx

from gcs.launcher import free_port
from tests.support.waiting import poll_until


def test_a_request_in_progress_holds_the_hub_no_longer_than_its_grace(tmp_path: Path) -> None:
    port = free_port()
    env = {key: value for key, value in os.environ.items() if not key.startswith("GCS_")}
    # The request in progress is a body still arriving: the hub would wait the body
    # timeout (30 s here) for it without a grace.
    env.update(GCS_SHUTDOWN_GRACE_S="1", GCS_BODY_TIMEOUT_S="30", GCS_VIZ_ENABLED="false")
    hub = subprocess.Popen(
        [sys.executable, "-m", "gcs", "hub", "--port", str(port), "--data-dir", str(tmp_path)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        base = f"http://127.0.0.1:{port}"

        def answers() -> bool:
            try:
                return httpx.get(f"{base}/api/v1/health").status_code == 200
            except httpx.HTTPError:
                return False

        poll_until(answers, 60, "the hub answering")
        with socket.create_connection(("127.0.0.1", port)) as held:
            held.sendall(
                b"POST /api/v1/auth/login HTTP/1.1\r\nHost: x\r\n"
                b"Content-Type: application/json\r\nContent-Length: 1000\r\n\r\n{"
            )
            # Answered after those bytes arrived: the login is in the app, awaiting its body.
            assert answers()
            asked = time.monotonic()
            hub.send_signal(signal.SIGTERM)
            hub.wait(timeout=20)
            took = time.monotonic() - asked
        assert took < 6, f"the hub took {took:.1f} s to stop"
    finally:
        if hub.poll() is None:
            hub.kill()
            hub.wait()
