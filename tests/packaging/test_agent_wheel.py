"""The agent-only wheel (agent/pyproject.toml) holds the agent and the leaf packages it
imports, and nothing of the hub, the simulator or the launcher: what a drone installs."""

from __future__ import annotations

import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path, PurePosixPath

import pytest

from tests.support.docs import page_holding

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = {"vehicle_agents", "protocol", "common"}
PIP_WHEEL = [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q"]
NEVER_ON_A_DRONE = {"backend", "simulator", "gcs", "frontend", "tests", "bench"}


@pytest.fixture(scope="module")
def agent_wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel, built as the deployer's guide says, with the hatchling of this environment (no
    network: the dev extra installs it)."""
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run(
        [*PIP_WHEEL, "--wheel-dir", str(out), str(ROOT / "agent")],
        check=True,
        timeout=120,
    )
    (wheel,) = out.glob("fleet_gcs_agent-*.whl")
    return wheel


def test_the_agent_wheel_holds_the_agent_and_its_leaves_only(agent_wheel: Path) -> None:
    with zipfile.ZipFile(agent_wheel) as wheel:
        names = [PurePosixPath(name) for name in wheel.namelist()]
    packages = {name.parts[0] for name in names if not name.parts[0].endswith(".dist-info")}
    assert packages == SHIPPED
    assert not packages & NEVER_ON_A_DRONE
    for package in SHIPPED:
        assert PurePosixPath(package, "__init__.py") in names
    # Sources only: no bytecode or stray files from the working tree.
    shipped = [name for name in names if name.parts[0] in SHIPPED]
    assert {name.suffix for name in shipped} == {".py"}
    assert PurePosixPath("vehicle_agents", "agent.py") in names


def test_the_agent_wheel_installs_gcs_agent(agent_wheel: Path) -> None:
    with zipfile.ZipFile(agent_wheel) as wheel:
        (entry_points,) = [n for n in wheel.namelist() if n.endswith("entry_points.txt")]
        scripts = wheel.read(entry_points).decode()
    assert "gcs-agent = vehicle_agents.cli:main" in scripts
    assert "gcs =" not in scripts  # the launcher is not there to run


def test_the_agent_project_has_the_base_dependencies() -> None:
    agent = tomllib.loads((ROOT / "agent" / "pyproject.toml").read_text())["project"]
    full = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert sorted(agent["dependencies"]) == sorted(full["dependencies"])
    assert agent["version"] == full["version"]
    assert full["scripts"]["gcs-agent"] == agent["scripts"]["gcs-agent"]


def test_the_agent_runs_from_its_wheel_without_the_rest(agent_wheel: Path, tmp_path: Path) -> None:
    """Unpacked alone, with the hub, the simulator and the launcher made unimportable,
    the agent imports whole and its command line answers."""
    with zipfile.ZipFile(agent_wheel) as wheel:
        wheel.extractall(tmp_path)
    script = (
        "import sys\n"
        f"sys.path.insert(0, {str(tmp_path)!r})\n"
        f"for name in {sorted(NEVER_ON_A_DRONE)!r}: sys.modules[name] = None\n"
        "import vehicle_agents, vehicle_agents.agent, vehicle_agents.cli\n"
        f"assert vehicle_agents.__file__.startswith({str(tmp_path)!r}), vehicle_agents.__file__\n"
        "sys.exit(vehicle_agents.cli.main(['--help']))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60, cwd=tmp_path
    )
    assert done.returncode == 0, done.stderr
    assert "--telemetry-rate-hz" in done.stdout


def test_the_offline_build_the_readme_gives_is_the_one_built_here() -> None:
    """An offline board cannot fetch the build backend: the deployer's guide says so, and
    gives
    the command this module builds with (PIP_WHEEL), which needs no package index."""
    readme = " ".join(page_holding("fetches the build backend (hatchling").read_text().split())
    backend = tomllib.loads((ROOT / "agent" / "pyproject.toml").read_text())["build-system"]
    assert backend["requires"] == ["hatchling>=1.21"]
    assert "fetches the build backend (hatchling" in readme
    assert "python3 -m pip wheel --no-deps --no-build-isolation -w dist ./agent" in readme
    assert {"--no-deps", "--no-build-isolation"} <= set(PIP_WHEEL)
