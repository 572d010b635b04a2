"""The table of guarantees (the reference guide) names a test on every row, and each
named test exists.

A row whose test was renamed or deleted would promise something nothing checks any more.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from tests.support.docs import page_holding

ROOT = Path(__file__).resolve().parents[3]
SECTION = "## Faults and hostile input: what is guaranteed"
TABLES = ("### Faults\n", "### Hostile input\n")  # the other subsections hold figures
NODE_ID = re.compile(r"(tests/[\w/]+\.py)::([\w:]+)")


def _section(text: str) -> str:
    start = text.index(SECTION)
    end = text.find("\n## ", start + len(SECTION))
    return text[start : end if end != -1 else len(text)]


def _subsection(section: str, heading: str) -> str:
    start = section.index(heading)
    end = section.find("\n### ", start + len(heading))
    return section[start : end if end != -1 else len(section)]


def _table_rows(section: str) -> list[str]:
    """The body rows of every table in the section: not the headers, not the rules."""
    lines = section.splitlines()
    rule = re.compile(r"\|[\s|:-]+\|")
    return [
        line
        for i, line in enumerate(lines)
        if line.startswith("|")
        and not rule.fullmatch(line)
        and not (i + 1 < len(lines) and rule.fullmatch(lines[i + 1]))
    ]


def _defines(path: Path, dotted: str) -> bool:
    """True if the module defines the test, as a function or as Class::method."""
    tree = ast.parse(path.read_text())
    names = dotted.split("::")
    scope: list[ast.stmt] = tree.body
    for name in names:
        found = next(
            (
                n
                for n in scope
                if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef)
                and n.name == name
            ),
            None,
        )
        if found is None:
            return False
        scope = found.body if isinstance(found, ast.ClassDef) else []
    return True


def test_every_row_names_a_test_that_exists() -> None:
    section = _section(page_holding(SECTION).read_text())
    rows = [row for heading in TABLES for row in _table_rows(_subsection(section, heading))]
    assert len(rows) >= 20, "the table of guarantees lost its rows"
    missing: list[str] = []
    for row in rows:
        node_ids = NODE_ID.findall(row)
        assert node_ids, f"a row names no test: {row[:120]}"
        for path, dotted in node_ids:
            if not (ROOT / path).is_file() or not _defines(ROOT / path, dotted):
                missing.append(f"{path}::{dotted}")
    assert not missing, f"the table of guarantees names tests that do not exist: {missing}"
