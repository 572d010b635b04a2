"""Write gcs_client/models.py, the Python client's typed models, from the two sources of
truth: the hub's OpenAPI document (``python -m backend.openapi_document``: every REST body
and answer) and the wire protocol's JSON Schema (``python -m protocol.messages``: the live
feed's messages, hub to client and client to hub).

    .venv/bin/python scripts/gen_client_models.py          # rewrite the module
    .venv/bin/python scripts/gen_client_models.py --check  # exit 1 if it is stale

tests/unit/gcs_client/test_client_models.py fails when the module and the sources differ, as the
dashboard's `npm run gen:api` check does for its TypeScript types.

Why generated rather than the client importing protocol/: protocol/ imports pymavlink (it
bounds each field by its MAVLink wire type), and the REST models live in the hub's
modules, which import FastAPI and SQLAlchemy. The client's wheel needs httpx, websockets
and pydantic only.

The models are for reading the hub's answers, so they are lenient where the hub is
strict: types and defaults are kept, bounds and patterns are left to the hub (which says
what it refused in its 422), and unknown fields are kept (``extra="allow"``) so that a
newer hub's additions do not break an older client.
"""

from __future__ import annotations

import argparse
import json
import keyword
import re
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

OUTPUT = ROOT / "gcs_client" / "models.py"

Schema = dict[str, Any]

HEADER = '''\
"""The hub's REST bodies and answers and the live feed's messages, as pydantic models.

GENERATED FILE - DO NOT EDIT. Written by scripts/gen_client_models.py from the hub's
OpenAPI document and the wire protocol's JSON Schema (tests/unit/gcs_client/test_client_models.py
checks it is in step with them). Lenient by design: no bounds (the hub checks those and
says what it refused), and fields a newer hub adds are kept, not refused.
"""

# ruff: noqa: E501

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter


class Model(BaseModel):
    """Every generated model: unknown fields kept, fields settable by name or alias."""

    model_config = ConfigDict(extra="allow", populate_by_name=True)
'''


class Generator:
    def __init__(self, schemas: dict[str, Schema], unions: dict[str, Schema] | None = None) -> None:
        self.schemas = schemas
        # The named unions (the commands, the feed's messages): a field that takes one of
        # them is typed by its name, not by the members written out again.
        self.unions = {_members(schema): name for name, schema in (unions or {}).items()}

    def class_name(self, ref: str) -> str:
        name = ref.rsplit("/", 1)[1]
        return re.sub(r"\W", "_", name)

    def annotation(self, schema: Schema) -> str:
        """The Python type of a JSON Schema."""
        if "$ref" in schema:
            return self.class_name(schema["$ref"])
        if "const" in schema:
            return f"Literal[{schema['const']!r}]"
        if "enum" in schema:
            return f"Literal[{', '.join(repr(value) for value in schema['enum'])}]"
        if "oneOf" in schema and (named := self.unions.get(_members(schema))):
            return named
        for union in ("anyOf", "oneOf"):
            if union in schema:
                parts = list(dict.fromkeys(self.annotation(part) for part in schema[union]))
                return " | ".join(parts)
        kind = schema.get("type")
        if isinstance(kind, list):
            return " | ".join(self.annotation({**schema, "type": k}) for k in kind)
        if kind == "string":
            return "str"
        if kind == "integer":
            return "int"
        if kind == "number":
            return "float"
        if kind == "boolean":
            return "bool"
        if kind == "null":
            return "None"
        if kind == "array":
            if "prefixItems" in schema:
                items = ", ".join(self.annotation(item) for item in schema["prefixItems"])
                return f"tuple[{items}]"
            if "items" in schema:
                return f"list[{self.annotation(schema['items'])}]"
            return "list[Any]"
        if kind == "object" or "additionalProperties" in schema:
            extra = schema.get("additionalProperties")
            if isinstance(extra, dict) and extra:
                return f"dict[str, {self.annotation(extra)}]"
            return "dict[str, Any]"
        return "Any"

    def definition(self, name: str, schema: Schema) -> str:
        """A class for an object schema; a type alias for anything else (an enum)."""
        if "properties" not in schema:
            return f"{name} = {self.annotation(schema)}\n"
        lines = [f"class {name}(Model):"]
        if description := schema.get("description"):
            lines.append(f"    {docstring(description)}")
            lines.append("")
        required = set(schema.get("required", []))
        for field, spec in schema["properties"].items():
            attribute = field if field.isidentifier() and not keyword.iskeyword(field) else None
            python_name = attribute or re.sub(r"\W", "_", field) + "_"
            annotation = self.annotation(spec)
            arguments = []
            if "const" in spec:
                # A tag (a message's type, a command's name): fills itself in.
                arguments.append(f"default={spec['const']!r}")
            elif field not in required:
                default = spec.get("default")
                if "default" not in spec and "None" not in annotation.split(" | "):
                    # Absent from the answer though not required: left out, not null.
                    annotation += " | None"
                arguments.append(f"default={default!r}" if not _mutable(default) else "")
                if _mutable(default):
                    arguments[-1] = f"default_factory=lambda: {default!r}"
            if attribute is None:
                arguments.append(f"alias={field!r}")
            if spec.get("description"):
                arguments.append(f"description={spec['description']!r}")
            if arguments:
                lines.append(f"    {python_name}: {annotation} = Field({', '.join(arguments)})")
            else:
                lines.append(f"    {python_name}: {annotation}")
        return "\n".join(lines) + "\n"


def _members(schema: Schema) -> frozenset[str]:
    return frozenset(json.dumps(part, sort_keys=True) for part in schema.get("oneOf", []))


def _mutable(value: object) -> bool:
    return isinstance(value, list | dict)


def docstring(text: str) -> str:
    text = text.strip().replace("\\", "\\\\").replace('"""', '\\"\\"\\"')
    return f'"""{text}"""'


def union_alias(generator: Generator, name: str, schema: Schema, doc: str) -> str:
    """A discriminated union (the feed's messages, the commands) and its TypeAdapter."""
    members = ", ".join(generator.annotation(part) for part in schema["oneOf"])
    tag = schema.get("discriminator", {}).get("propertyName", "name")
    return (
        f"# {doc}\n"
        f"{name} = Annotated[{members.replace(', ', ' | ')}, Field(discriminator={tag!r})]\n"
        f"{name.upper()}_ADAPTER: TypeAdapter[{name}] = TypeAdapter({name})\n"
    )


def sources() -> tuple[Schema, Schema]:
    from backend.openapi_document import openapi_document
    from protocol.messages import json_schema

    return openapi_document(), json_schema()


def merged_schemas(openapi: Schema, protocol: Schema) -> dict[str, Schema]:
    """Every named schema of both sources; a name both use must mean the same thing."""
    merged: dict[str, Schema] = dict(openapi["components"]["schemas"])
    for direction in ("hub_to_client", "client_to_hub"):
        for name, schema in protocol[direction]["$defs"].items():
            schema = json.loads(json.dumps(schema).replace("#/$defs/", "#/components/schemas/"))
            known = merged.get(name)
            if known is not None and _shape(known) != _shape(schema):
                raise SystemExit(f"{name} differs between the OpenAPI document and the protocol")
            merged.setdefault(name, schema)
    return merged


def _shape(schema: Schema) -> str:
    """What the generated code depends on: the types and defaults, not the bounds."""
    generator = Generator({})
    if "properties" not in schema:
        return generator.annotation(schema)
    return json.dumps(
        {
            field: (generator.annotation(spec), spec.get("default"))
            for field, spec in schema["properties"].items()
        },
        sort_keys=True,
    )


def generate(openapi: Schema, protocol: Schema) -> str:
    schemas = merged_schemas(openapi, protocol)
    feed = {
        key: json.loads(json.dumps(value).replace("#/$defs/", "#/components/schemas/"))
        for key, value in protocol["hub_to_client"].items()
        if key != "$defs"
    }
    outgoing = {
        key: json.loads(json.dumps(value).replace("#/$defs/", "#/components/schemas/"))
        for key, value in protocol["client_to_hub"].items()
        if key != "$defs"
    }
    command_body = openapi["paths"]["/api/v1/vehicles/{vehicle_id}/commands"]["post"]
    commands = command_body["requestBody"]["content"]["application/json"]["schema"]
    generator = Generator(
        schemas, {"FeedMessage": feed, "ClientMessage": outgoing, "Command": commands}
    )
    blocks = [HEADER]
    for name in sorted(schemas):
        blocks.append(generator.definition(generator.class_name(f"#/{name}"), schemas[name]))
    blocks.append(
        union_alias(generator, "FeedMessage", feed, "What the hub sends on the live feed.")
    )
    blocks.append(
        union_alias(generator, "ClientMessage", outgoing, "What a client sends on the feed.")
    )
    blocks.append(
        union_alias(generator, "Command", commands, "One vehicle command, picked by its name.")
    )
    names = sorted(generator.class_name(f"#/{name}") for name in schemas)
    blocks.append(
        "# Models that name one another are completed once every class exists.\n"
        f"for _model in ({', '.join(n for n in names if 'properties' in schemas[n])},):\n"
        "    _model.model_rebuild()\n"
    )
    return "\n\n".join(block.rstrip("\n") + "\n" for block in blocks)


def formatted(source: str) -> str:
    """The module as ruff formats it, so the committed file passes `ruff format --check`."""
    import subprocess

    ruff = Path(sys.executable).with_name("ruff")
    return subprocess.run(
        [str(ruff), "format", "--stdin-filename", str(OUTPUT), "-"],
        input=source,
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    ).stdout


def current() -> str:
    return formatted(generate(*sources()))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if the module is stale")
    args = parser.parse_args()
    text = current()
    if args.check:
        if OUTPUT.read_text() != text:
            print(f"{OUTPUT.relative_to(ROOT)} is stale: run scripts/gen_client_models.py")
            return 1
        return 0
    OUTPUT.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
