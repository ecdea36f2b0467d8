"""The layout issue's limits, checked on the package source (README: Layout; docs/architecture.md).

- no folder of the package holds more than 10 modules (``__init__`` not counted);
- no module is over 600 lines;
- no function or method is over 60 lines unless its docstring says why (a line starting "Long:").
"""
from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "c1surf"
MAX_MODULES, MAX_LINES, MAX_FUNCTION = 10, 600, 60


def _modules():
    return sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


def test_no_folder_holds_more_than_ten_modules():
    folders = {}
    for path in _modules():
        if path.name != "__init__.py":
            folders.setdefault(path.parent, []).append(path.name)
    crowded = {str(k.relative_to(PACKAGE.parent)): len(v) for k, v in folders.items() if len(v) > MAX_MODULES}
    assert not crowded


def test_no_module_is_over_600_lines():
    long = {str(p.relative_to(PACKAGE.parent)): n for p in _modules() if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not long


def long_functions() -> dict:
    """{"module:function": lines} of every function over the limit whose docstring gives no reason."""
    found = {}
    for path in _modules():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                length = node.end_lineno - node.lineno + 1
                doc = ast.get_docstring(node) or ""
                if length > MAX_FUNCTION and not any(line.startswith("Long:") for line in doc.splitlines()):
                    found[f"{path.relative_to(PACKAGE.parent)}:{node.name}"] = length
    return found


def test_no_function_is_over_60_lines_without_a_reason():
    assert not long_functions()
