"""The type stubs cover the native module: every public name and method has a stub."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import regatta
from regatta import _regatta

STUBS = Path(regatta.__file__).with_name("_regatta.pyi")


def stubbed() -> dict[str, set[str]]:
    tree = ast.parse(STUBS.read_text())
    names: dict[str, set[str]] = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            names[node.name] = {
                n.name for n in node.body if isinstance(n, (ast.FunctionDef, ast.AnnAssign)) and hasattr(n, "name")
            }
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = set()
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names[node.target.id] = set()
    return names


def test_every_public_name_has_a_stub():
    stubs = stubbed()
    public = [n for n in dir(_regatta) if not n.startswith("_") or n == "__version__"]
    assert set(public) <= set(stubs), set(public) - set(stubs)
    for name in public:
        value = getattr(_regatta, name)
        if inspect.isclass(value) and not issubclass(value, BaseException):
            members = {m for m in vars(value) if not m.startswith("_") or m in ("__getitem__",)}
            assert members <= stubs[name] | {"__new__"}, (name, members - stubs[name])


def test_py_typed_marks_the_package():
    assert STUBS.with_name("py.typed").exists()
