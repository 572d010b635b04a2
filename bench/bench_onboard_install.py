"""What an onboard install holds: the agent-only install measured as docs/deployer.md states it.

    .venv/bin/python bench/bench_onboard_install.py            # options: --seconds 60

In a temporary folder, as docs/deployer.md's onboard steps do it: builds the agent wheel
(./agent), makes a fresh venv with this Python, installs requirements/agent.txt with
--require-hashes and the wheel with --no-deps, then measures

- the install's size on disk in MiB (as ``du -h`` counts it), whole and for the
  biggest parts (pymavlink and its dialects, pip + setuptools, lxml), before and after
  ``python -m vehicle_agents.slim_install`` and ``pip uninstall setuptools``;
- the agent's start-up imports (everything ``gcs-agent`` loads before it connects: the
  command line, the agent and the MAVLink dialect): CPU and wall time, and RSS after,
  the median of several runs (CPU time: wall time means little on a shared machine);
- the running agent's RSS and CPU share: ``gcs-agent`` from that venv against this
  checkout's simulator (``gcs sim``, real time, 10 Hz telemetry) and hub (``gcs hub``),
  sampled once a second after a warm-up.

Prints the figures as a table; asserts nothing. The machine it runs on is not the drone's:
docs/deployer.md says which machine the figures are from.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.agent_footprint.processes import cpu_and_rss, spawn, stop, wait_for_hub
from gcs.launcher import free_port

ROOT = Path(__file__).resolve().parent.parent
VEHICLE_ID = "onboard_bench"
TOKEN = "gcs_v_" + "c" * 40
PASSWORD = "bench-admin-password"
IMPORT_RUNS = 7
# What gcs-agent imports before it opens any link: its command line, the agent (which
# brings the dialect, pydantic, websockets, ...). The figures are printed as JSON.
IMPORT_PROBE = """
import json, resource, time
started = time.perf_counter()
import vehicle_agents.cli, vehicle_agents.agent
wall = time.perf_counter() - started
usage = resource.getrusage(resource.RUSAGE_SELF)
rss_kb = int(next(l for l in open('/proc/self/status') if l.startswith('VmRSS')).split()[1])
print(json.dumps({"import_s": wall, "cpu_s": usage.ru_utime + usage.ru_stime,
                  "rss_mb": rss_kb / 1024}))
"""
MIB = 1024 * 1024  # du -h and ls -h count in these ("M")


def du_bytes(path: Path) -> int:
    """Allocated size, as du counts it (each hard link once)."""
    seen: set[tuple[int, int]] = set()
    total = 0
    for folder, _, names in os.walk(path):
        for name in [".", *names]:
            with contextlib.suppress(OSError):
                info = os.lstat(os.path.join(folder, name))
                if (info.st_dev, info.st_ino) not in seen:
                    seen.add((info.st_dev, info.st_ino))
                    total += info.st_blocks * 512
    return total


def run(*args: str | Path, cwd: Path | None = None) -> str:
    done = subprocess.run(
        [str(a) for a in args], cwd=cwd, capture_output=True, text=True, check=False
    )
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(map(str, args))} failed:\n{done.stdout}\n{done.stderr}")
    return done.stdout


def sizes(venv: Path) -> dict[str, float]:
    (site,) = venv.glob("lib/python3*/site-packages")
    parts = {
        "total": [venv],
        "pymavlink": [site / "pymavlink"],
        "pymavlink dialects": [site / "pymavlink" / "dialects"],
        "pip + setuptools": [
            *site.glob("pip"),
            *site.glob("pip-*"),
            *site.glob("setuptools*"),
            *site.glob("pkg_resources"),
            *site.glob("_distutils_hack"),
        ],
        "lxml": [site / "lxml"],
    }
    return {
        name: sum(du_bytes(path) for path in paths if path.exists()) / MIB
        for name, paths in parts.items()
    }


def import_figures(python: Path, workdir: Path) -> dict[str, float]:
    """Median of IMPORT_RUNS start-ups (bytecode already compiled by pip, as on a drone
    after the first start)."""
    runs = [json.loads(run(python, "-c", IMPORT_PROBE, cwd=workdir)) for _ in range(IMPORT_RUNS)]
    return {key: statistics.median(r[key] for r in runs) for key in runs[0]}


def agent_figures(
    gcs_agent: Path, workdir: Path, warmup_s: float, seconds: float
) -> dict[str, float]:
    """RSS and CPU of gcs-agent flying nothing, connected to a simulator and a hub."""
    sim_port, hub_port = free_port(), free_port()
    hub_url = f"http://127.0.0.1:{hub_port}"
    dev_python = sys.executable  # the checkout's own venv: hub and simulator
    sim = spawn(
        [dev_python, "-m", "gcs", "sim", "--listen", f"tcp:127.0.0.1:{sim_port}"],
        workdir / "sim.log",
    )
    hub = spawn(
        [
            dev_python,
            "-m",
            "gcs",
            "--log-level",
            "WARNING",
            "hub",
            "--port",
            str(hub_port),
            "--data-dir",
            str(workdir / "hub"),
        ],
        workdir / "hub.log",
        {
            "GCS_ENVIRONMENT": "development",
            "GCS_ADMIN_PASSWORD": PASSWORD,
            "GCS_AGENT_TOKENS": f"{VEHICLE_ID}={TOKEN}",
        },
    )
    agent = None
    try:
        wait_for_hub(hub_url, hub)
        env = {k: v for k, v in os.environ.items() if not k.startswith(("GCS_", "MAVLINK"))}
        env |= {"GCS_AGENT_TOKEN": TOKEN, "PATH": f"{gcs_agent.parent}:{env.get('PATH', '')}"}
        log_path = workdir / "agent.log"
        with log_path.open("wb") as log_file:
            agent = subprocess.Popen(
                [
                    gcs_agent,
                    "--vehicle-id",
                    VEHICLE_ID,
                    "--fcu",
                    f"tcp:127.0.0.1:{sim_port}",
                    "--hub",
                    f"ws://127.0.0.1:{hub_port}",
                    "--outbox-dir",
                    str(workdir / "outbox"),
                ],
                stdout=log_file,
                stderr=subprocess.STDOUT,
                env=env,
                cwd=workdir,
                start_new_session=True,
            )
        time.sleep(warmup_s)  # connecting, the handshake, the stream requests
        if not connected(hub_url):
            raise SystemExit(f"the agent did not connect; see {log_path}")
        cpu_first, rss_first = cpu_and_rss(agent.pid)
        started = time.monotonic()
        rss: list[float] = []
        while time.monotonic() - started < seconds:
            time.sleep(1.0)  # the sampling period
            if agent.poll() is not None:
                raise SystemExit(f"the agent exited with {agent.returncode}; see {log_path}")
            rss.append(cpu_and_rss(agent.pid)[1])
        cpu_last, rss_last = cpu_and_rss(agent.pid)
        elapsed = time.monotonic() - started
        return {
            "rss_connected_mb": rss_first,
            "rss_end_mb": rss_last,
            "rss_max_mb": max(rss),
            "cpu_pct": 100 * (cpu_last - cpu_first) / elapsed,
            "seconds": elapsed,
        }
    finally:
        stop(agent)
        stop(hub)
        stop(sim)


def connected(hub_url: str) -> bool:
    form = f"username=admin&password={PASSWORD}".encode()
    with urllib.request.urlopen(f"{hub_url}/api/v1/auth/token", data=form, timeout=5) as answer:
        token = json.load(answer)["access_token"]
    request = urllib.request.Request(
        f"{hub_url}/api/v1/vehicles/{VEHICLE_ID}", headers={"Authorization": f"Bearer {token}"}
    )
    with urllib.request.urlopen(request, timeout=5) as answer:
        return bool(json.load(answer)["connected"])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="agent measured (60)")
    parser.add_argument("--warmup", type=float, default=10.0, help="before sampling (10)")
    parser.add_argument("--keep", action="store_true", help="keep the temporary folder")
    args = parser.parse_args()

    workdir = Path(tempfile.mkdtemp(prefix="bench_onboard_"))
    try:
        venv, dist = workdir / "venv", workdir / "dist"
        run(sys.executable, "-m", "pip", "wheel", "--no-deps", "-w", dist, ROOT / "agent")
        (wheel,) = dist.glob("fleet_gcs_agent-*.whl")
        run(sys.executable, "-m", "venv", venv)
        pip = venv / "bin" / "pip"
        run(pip, "install", "--require-hashes", "-r", ROOT / "requirements" / "agent.txt")
        run(pip, "install", "--no-deps", wheel)
        python = venv / "bin" / "python"

        rows = {"installed": sizes(venv)}
        imports = import_figures(python, workdir)
        running = agent_figures(venv / "bin" / "gcs-agent", workdir, args.warmup, args.seconds)
        run(python, "-m", "vehicle_agents.slim_install")
        rows["after slim_install"] = sizes(venv)
        slim_imports = import_figures(python, workdir)
        slim_running = agent_figures(venv / "bin" / "gcs-agent", workdir, args.warmup, args.seconds)
        run(pip, "uninstall", "--yes", "setuptools")
        rows["and without setuptools"] = sizes(venv)
    finally:
        if args.keep:
            print(f"kept {workdir}")
        else:
            shutil.rmtree(workdir, ignore_errors=True)

    print(f"Python {sys.version.split()[0]} on {os.uname().machine}, {os.cpu_count()} CPUs")
    print(f"{'size on disk, MB':26}" + "".join(f"{name:>20}" for name in rows["installed"]))
    for label, row in rows.items():
        print(f"{label:26}" + "".join(f"{value:20.1f}" for value in row.values()))
    for label, figures, agent in (
        ("installed", imports, running),
        ("after slim_install", slim_imports, slim_running),
    ):
        print(
            f"{label}: start-up and imports {figures['cpu_s']:.2f} s CPU (imports"
            f" {figures['import_s']:.2f} s wall),"
            f" {figures['rss_mb']:.1f} MiB RSS after; agent RSS {agent['rss_connected_mb']:.1f} MiB"
            f" connected, {agent['rss_end_mb']:.1f} MiB after {agent['seconds']:.0f} s"
            f" (max {agent['rss_max_mb']:.1f}), {agent['cpu_pct']:.1f} % of one core"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
