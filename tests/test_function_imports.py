"""An import inside a function of ``app/`` is there for start-up time (or to break a cycle)
and says so: on its line, in a comment just above its block of imports, or for the whole
module in a module-level comment that starts with ``# Imports inside functions:``.

Every command, job process and test subprocess pays for what ``app`` imports at start, so
heavy modules (scikit-learn through the catalogue, matplotlib, alembic) load where they are
used; an import hidden in a function for no such reason only hides a dependency.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

APP = Path(__file__).resolve().parents[1] / "app"
MARKER = "# Imports inside functions:"


def _unexplained(path: Path) -> list[str]:
    lines = path.read_text().splitlines()
    if any(line.startswith(MARKER) for line in lines):
        return []
    found = []
    for node in ast.walk(ast.parse("\n".join(lines))):
        if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        for inner in ast.walk(node):
            if isinstance(inner, ast.Import | ast.ImportFrom):
                block = _block(lines, inner.lineno - 1)
                above = lines[block[0] - 1].strip() if block[0] > 0 else ""
                if not above.startswith("#") and not any("#" in lines[i] for i in block):
                    line = lines[inner.lineno - 1]
                    found.append(f"{path.relative_to(APP.parent)}:{inner.lineno}: {line.strip()}")
    return found


def _block(lines: list[str], index: int) -> range:
    """The indices of the run of import lines around ``lines[index]``."""
    first, last = index, index
    while first > 0 and lines[first - 1].strip().startswith(("import ", "from ")):
        first -= 1
    while last + 1 < len(lines) and lines[last + 1].strip().startswith(("import ", "from ")):
        last += 1
    return range(first, last + 1)


@pytest.mark.parametrize("path", sorted(APP.rglob("*.py")), ids=lambda p: str(p.relative_to(APP)))
def test_an_import_inside_a_function_says_why(path: Path) -> None:
    unexplained = _unexplained(path)
    assert not unexplained, "say why (start-up time, a cycle) or move to the top:\n" + "\n".join(
        unexplained
    )
