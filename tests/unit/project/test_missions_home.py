"""The mission planners (the survey's `backend.survey.planning`, the formation's planner,
route and schemas) and the safety rules they are checked by (`backend.safety`'s rule
modules) are pure domain logic that knows nothing of HTTP, storage or the agent, so that
planners can be tested alone."""

from __future__ import annotations

import subprocess
import sys

# Imported in a fresh interpreter: this test process has long since loaded all of these.
_PROBE = """
import importlib, pkgutil, sys
import backend.survey.planning
for module in pkgutil.iter_modules(backend.survey.planning.__path__):
    importlib.import_module("backend.survey.planning." + module.name)
import backend.formation.planner, backend.formation.route, backend.formation.schemas
import backend.safety.commands, backend.safety.service
print("\\n".join(sorted(sys.modules)))
"""
_DOMAIN_MAY_NOT_IMPORT = ("fastapi", "starlette", "sqlalchemy", "vehicle_agents", "simulator")
_DOMAIN_MAY_NOT_REACH = ("backend.api", "backend.storage", "backend.hub", "backend.realtime")


def _loaded(probe: str) -> list[str]:
    result = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=60
    )
    return result.stdout.split()


def test_the_missions_module_knows_nothing_of_http_storage_or_the_agent() -> None:
    probe = _PROBE.replace("import backend.safety.commands, backend.safety.service\n", "")
    loaded = _loaded(probe)
    assert "backend.safety.mission_check" in loaded
    wrong = [
        name
        for name in loaded
        if name.split(".")[0] in _DOMAIN_MAY_NOT_IMPORT or name.startswith(_DOMAIN_MAY_NOT_REACH)
    ]
    assert wrong == []


def test_the_hub_checks_missions_without_importing_the_agent() -> None:
    loaded = _loaded(_PROBE)
    assert "backend.safety.service" in loaded
    assert [name for name in loaded if name.split(".")[0] == "vehicle_agents"] == []
