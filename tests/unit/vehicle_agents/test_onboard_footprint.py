"""What an onboard install loads and holds: only the dialect the agent speaks."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from vehicle_agents.slim_install import main, slim, unneeded_files


def test_the_agent_loads_one_dialect() -> None:
    """mavutil would also import the 2.6 MB MAVLink 1 "all" dialect on its own import;
    the agent's process never holds it (a fresh interpreter, as the agent starts)."""
    script = (
        "import sys\n"
        "from vehicle_agents.fcu.dialect import mavutil\n"
        "module = mavutil()\n"
        "loaded = sorted(n for n, m in sys.modules.items()\n"
        "                if n.count('.') == 3 and n.startswith('pymavlink.dialects.')\n"
        "                and m is not None)\n"
        "print(module.mavlink.__name__, loaded)\n"
    )
    # As the agent starts: an earlier test's import of mavutil in this process sets
    # MAVLINK_DIALECT=all in the environment a child would inherit.
    env = {k: v for k, v in os.environ.items() if k not in ("MAVLINK_DIALECT", "MAVLINK20")}
    done = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
        env=env,
    )
    dialect = "pymavlink.dialects.v20.ardupilotmega"
    assert done.stdout.strip() == f"{dialect} ['{dialect}']"


# The agent's RSS bar (DESIGN.md: 60 MB at 200 messages/s); its imports alone took 47 MiB
# when measured (docs/deployer.md, "What an onboard install holds"), so this leaves room to run.
IMPORTED_RSS_BUDGET_MIB = 52
NEVER_IMPORTED = {
    "backend",
    "simulator",
    "gcs",
    "bench",  # the hub, the simulator, the launcher
    "fastapi",
    "starlette",
    "uvicorn",
    "sqlalchemy",
    "httpx",
    "viser",  # the hub's
    "numpy",
    "lxml",  # pymavlink's optional numpy, its generator's lxml: 10+ MiB each
}


def test_the_agents_start_up_imports_nothing_of_the_hub_and_fit_its_budget() -> None:
    """What gcs-agent loads before it connects, in a fresh interpreter of the dev venv,
    which has the hub's packages too: none of them, and a bounded RSS."""
    script = (
        "import sys\n"
        "import vehicle_agents.cli, vehicle_agents.agent\n"
        "status = open('/proc/self/status').read().splitlines()\n"
        "rss_kb = next(int(line.split()[1]) for line in status if line.startswith('VmRSS'))\n"
        "print(rss_kb / 1024, ' '.join(sorted({name.split('.')[0] for name in sys.modules})))\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("MAVLINK_DIALECT", "MAVLINK20")}
    done = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
        env=env,
    )
    rss_mib, loaded = done.stdout.split(" ", 1)
    assert NEVER_IMPORTED & set(loaded.split()) == set()
    assert float(rss_mib) < IMPORTED_RSS_BUDGET_MIB


def _fake_pymavlink(root: Path) -> Path:
    for version in ("v10", "v20"):
        folder = root / "dialects" / version
        (folder / "__pycache__").mkdir(parents=True)
        for name in ("__init__", "ardupilotmega", "common", "minimal", "all", "storm32"):
            (folder / f"{name}.py").write_text("x = 1\n")
            (folder / "__pycache__" / f"{name}.cpython-311.pyc").write_bytes(b"\0")
            if name != "__init__":
                (folder / f"{name}.xml").write_text("<mavlink/>")
    (root / "mavutil.py").write_text("")
    return root


def test_slimming_keeps_the_agents_dialects_and_all_else(tmp_path: Path) -> None:
    root = _fake_pymavlink(tmp_path / "pymavlink")
    assert slim(root) > 0
    left = {p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file()}
    for version in ("v10", "v20"):
        for name in ("__init__", "ardupilotmega", "common", "minimal"):
            assert f"dialects/{version}/{name}.py" in left
            assert f"dialects/{version}/__pycache__/{name}.cpython-311.pyc" in left
        assert not any(f"/{version}/all" in path or "storm32" in path for path in left)
    assert "mavutil.py" in left
    assert not list(unneeded_files(root))


def test_a_dialect_chosen_by_the_operator_is_kept_only_when_asked(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("MAVLINK_DIALECT", "storm32")
    assert main(["--dry-run"]) == 2
    assert "--keep storm32" in capsys.readouterr().err
    root = _fake_pymavlink(tmp_path / "pymavlink")
    slim(root, keep={"ardupilotmega", "common", "minimal", "storm32"})
    assert (root / "dialects" / "v20" / "storm32.py").exists()
