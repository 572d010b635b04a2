"""JSON request bodies hold finite numbers only.

Python's parser accepts ``NaN``, ``Infinity`` and ``-Infinity``, which JSON (RFC 8259) does
not have, and reads a number too large for a double (``1e309``, ``-1E400``) as an infinity.
Let through, they pass any float field without bounds, reach the vehicle, and break the
answer itself (a 422 echoing the input cannot be serialised). So a body that holds one,
however it is spelled, is refused at parse time with a 422 that names where it is.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Coroutine, Iterator
from typing import Any

from fastapi import HTTPException
from fastapi.routing import APIRoute
from starlette.requests import Request
from starlette.responses import Response


class _NonFinite:
    """Stands in for a non-finite number while the body is parsed."""

    def __init__(self, text: str, why: str) -> None:
        self.text = text
        self.why = why


def _non_finite_at(value: object, path: tuple[str | int, ...]) -> Iterator[tuple[Any, ...]]:
    if isinstance(value, _NonFinite):
        yield (*path, value)
    elif isinstance(value, dict):
        for key, item in value.items():
            yield from _non_finite_at(item, (*path, key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            yield from _non_finite_at(item, (*path, index))


def parse_finite_json(body: bytes) -> Any:
    """The parsed body; raises a 422 listing every NaN, Infinity or number too large for a
    double, by location."""
    found = False

    def constant(text: str) -> _NonFinite:
        nonlocal found
        found = True
        return _NonFinite(text, "is not a JSON number")

    def number(text: str) -> float | _NonFinite:
        # Only numbers with a fraction or an exponent come here (integers stay exact, and
        # pydantic refuses one too large for a float field by name).
        value = float(text)
        if math.isfinite(value):
            return value
        nonlocal found
        found = True
        return _NonFinite(text, "is too large for a number (a 64-bit float)")

    try:
        parsed = json.loads(body, parse_constant=constant, parse_float=number)
    except json.JSONDecodeError:
        raise  # FastAPI answers these with its own 422, naming the position
    except (ValueError, RecursionError) as error:
        # Not UTF-8, an integer past the interpreter's digit limit, or nesting past the
        # parser's depth: as unparsable as a syntax error, so the same 422 (not a 400).
        detail = [
            {"loc": ["body"], "msg": f"the body is not valid JSON: {error}", "type": "json_invalid"}
        ]
        raise HTTPException(status_code=422, detail=detail) from None
    if not found:
        return parsed
    detail = [
        {
            "loc": ["body", *where[:-1]],
            "msg": f"{where[-1].text} {where[-1].why}; send a finite number",
            "type": "finite_number",
            "input": where[-1].text,
        }
        for where in _non_finite_at(parsed, ())
    ]
    raise HTTPException(status_code=422, detail=detail)


class FiniteJsonRequest(Request):
    async def json(self) -> Any:
        if not hasattr(self, "_json"):
            self._json = parse_finite_json(await self.body())
        return self._json


class FiniteJsonRoute(APIRoute):
    """A route whose JSON body is parsed by ``parse_finite_json``."""

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        handler = super().get_route_handler()

        async def finite_json_handler(request: Request) -> Response:
            return await handler(FiniteJsonRequest(request.scope, request.receive))

        return finite_json_handler
