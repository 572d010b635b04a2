"""`python -m protocol.messages` prints the wire's JSON schema (the dashboard's types and
the client models are generated from it)."""

from __future__ import annotations

import json
import sys

from protocol.messages.directions import json_schema

json.dump(json_schema(), sys.stdout, indent=2)
sys.stdout.write("\n")
