"""Prints the hub's OpenAPI document as JSON: ``python -m backend.openapi_document``.

The dashboard's REST types (``frontend/src/generated/api.ts``) are generated from it by
``npm run gen:api``, and tests/unit/frontend/test_frontend_api_types.py checks they still match.
"""

from __future__ import annotations

import json
import sys
from typing import Any

from backend.app import create_app
from backend.settings import HubSettings


def openapi_document() -> dict[str, Any]:
    """The document the hub serves at ``/openapi.json``, for the default settings.

    The settings are built from their defaults alone (``model_construct`` reads no
    environment), so the document, and the types made from it, do not depend on the
    shell that generates them. Building the app opens no database and starts nothing.
    """
    return create_app(HubSettings.model_construct()).openapi()


def main() -> None:
    json.dump(openapi_document(), sys.stdout, indent=2)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
