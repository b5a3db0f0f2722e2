"""The package's folders are its layers (manual §10): each imports only what the table there says.

Read from the source (every ``import`` statement, also inside functions), so an import added
in a function body that a test never runs is caught too. The only imports left out are those
inside a module's ``__getattr__``: the former names of moved functions, resolved on use.
"""

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "softtip"

#: layer -> the other layers (or single modules) it may import
ALLOWED = {
    "core": {"errors", "io.tomlfile"},
    "estimator": {"core", "errors", "io.tomlfile"},
    "io": {"core", "errors", "estimator", "ros"},
    "calibration": {"core", "errors", "io"},
    "sim": {"core", "errors", "estimator", "io", "viz"},
    "fusion": {"core", "errors", "estimator", "io", "viz"},
    "viz": {"core", "errors", "estimator"},
    "ros": {"core", "errors", "estimator", "io"},
    "testing": {"core", "errors", "io"},
}


def _imports(path: Path):
    """``(line, module)`` of every absolute ``softtip.…`` import outside ``__getattr__``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skip = {id(n) for f in ast.walk(tree) if isinstance(f, ast.FunctionDef) and f.name == "__getattr__" for n in ast.walk(f)}
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        else:
            continue
        for name in names:
            if name.startswith("softtip."):
                yield node.lineno, name


@pytest.mark.parametrize("layer", sorted(ALLOWED))
def test_a_layer_imports_only_what_the_manual_says(layer):
    wrong = []
    for path in sorted((SRC / layer).rglob("*.py")):
        for line, module in _imports(path):
            parts = module.split(".")[1:]
            if parts[0] == layer:
                continue
            if parts[0] not in ALLOWED[layer] and ".".join(parts[:2]) not in ALLOWED[layer]:
                wrong.append(f"{path.relative_to(SRC.parent)}:{line}: imports {module}")
    assert not wrong, "\n".join(wrong)


def test_the_check_sees_an_import_inside_a_function(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("def g():\n    from softtip.sim import x\n\ndef __getattr__(name):\n    from softtip.cli import y\n")
    assert list(_imports(f)) == [(2, "softtip.sim")]
