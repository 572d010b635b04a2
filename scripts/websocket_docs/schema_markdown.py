"""The protocol's JSON Schema as Markdown: a message's heading, its fields' table, their
types (linked to the page's anchors) and limits in words."""

from __future__ import annotations

import json
import typing
from typing import Any

from protocol import messages

Schema = dict[str, Any]


def union_members(alias: Any) -> list[str]:
    """The message classes of a direction's discriminated union, in declaration order."""
    union = typing.get_args(alias)[0]
    return [member.__name__ for member in typing.get_args(union) or (union,)]


def all_definitions() -> dict[str, Schema]:
    definitions: dict[str, Schema] = {}
    for adapter in (
        messages.agent_to_hub,
        messages.hub_to_agent,
        messages.client_to_hub,
        messages.hub_to_client,
        messages.command_adapter,
    ):
        definitions.update(adapter.json_schema()["$defs"])
    return definitions


def anchor(name: str) -> str:
    return name.lower()


def type_of(schema: Schema) -> str:
    if "$ref" in schema:
        name = schema["$ref"].rsplit("/", 1)[1]
        return f"[{name}](#{anchor(name)})"
    if "const" in schema:
        return f"`{json.dumps(schema['const'])}`"
    if "enum" in schema:
        return " or ".join(f"`{json.dumps(value)}`" for value in schema["enum"])
    if "anyOf" in schema:
        return " or ".join(type_of(option) for option in schema["anyOf"])
    if "oneOf" in schema:
        mapping = schema.get("discriminator", {}).get("mapping", {})
        key = schema.get("discriminator", {}).get("propertyName", "type")
        return f"one of the [commands](#commands), by `{key}`" if mapping else "one of several"
    kind = schema.get("type")
    if kind == "array" and "prefixItems" in schema:  # a tuple: (east, north, up), say
        return "[" + ", ".join(type_of(item) for item in schema["prefixItems"]) + "]"
    if kind == "array":
        return f"list of {type_of(schema['items'])}"
    if kind == "object" and isinstance(schema.get("additionalProperties"), dict):
        return f"object of {type_of(schema['additionalProperties'])}"
    return str(kind)


def number(value: float) -> str:
    return str(value) if isinstance(value, int) else f"{value:g}"


def limits_of(schema: Schema) -> list[str]:
    """The constraints a value must meet, in words."""
    limits: list[str] = []
    for option in schema.get("anyOf", [schema]):
        bounds = []
        for key, word in (
            ("minimum", "≥"),
            ("exclusiveMinimum", ">"),
            ("maximum", "≤"),
            ("exclusiveMaximum", "<"),
        ):
            if key in option:
                bounds.append(f"{word} {number(option[key])}")
        if bounds:
            limits.append(" and ".join(bounds))
        for unit, low_key, high_key in (
            ("chars", "minLength", "maxLength"),
            ("items", "minItems", "maxItems"),
        ):
            low, high = option.get(low_key, 0), option.get(high_key)
            if low and high is not None:
                limits.append(f"{low} to {high} {unit}")
            elif low:
                limits.append(f"at least {low} {unit}")
            elif high is not None:
                limits.append(f"at most {high} {unit}")
        if "pattern" in option:
            limits.append(f"matches `{option['pattern']}`")
    return limits


def cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def field_table(schema: Schema) -> list[str]:
    properties: dict[str, Schema] = schema.get("properties", {})
    if not properties:
        return ["No fields."]
    required = set(schema.get("required", []))
    lines = ["| field | type | required or default | meaning |", "| --- | --- | --- | --- |"]
    for name, prop in properties.items():
        if name in required:
            presence = "required"
        elif "default" in prop:
            presence = f"`{json.dumps(prop['default'])}`"
        else:
            presence = "optional"
        description = " ".join(prop.get("description", "").split())
        if not description.endswith("..."):  # "multirotor, rover, ..." keeps its dots
            description = description.removesuffix(".")
        meaning = "; ".join(part for part in (description, ", ".join(limits_of(prop))) if part)
        lines.append(f"| `{name}` | {cell(type_of(prop))} | {presence} | {cell(meaning)} |")
    return lines


def description_of(schema: Schema) -> list[str]:
    text = schema.get("description")
    return [" ".join(text.split()), ""] if text else []


def message_section(
    name: str, schema: Schema, direction: str, anchored: set[str] | None = None
) -> list[str]:
    """A message's heading and fields; its anchor once per page (``anchored`` holds those
    already written: ping and pong go both ways, and links lead to the first)."""
    tag = schema["properties"]["type"]["const"]
    target = anchor(name)
    if anchored is not None:
        if target in anchored:
            target = ""
        anchored.add(target)
    return [
        *([f'<a id="{target}"></a>'] if target else []),
        f"#### `{tag}` ({direction})",
        "",
        *description_of(schema),
        *field_table(schema),
        "",
    ]


def type_section(name: str, schema: Schema) -> list[str]:
    return [f"### {name}", "", *description_of(schema), *field_table(schema), ""]
