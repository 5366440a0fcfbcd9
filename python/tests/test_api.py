"""The type stubs list exactly the module's public names, so that editors complete what exists."""

import ast
import pathlib

import hovs


def stub_names():
    tree = ast.parse((pathlib.Path(hovs.__file__).parent / "__init__.pyi").read_text())
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return names, {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}


def test_stubs_match_the_module():
    names, classes = stub_names()
    public = set(hovs.__all__) | {"__version__"}
    assert names == public
    for name, cls in classes.items():
        members = {n.name for n in cls.body if isinstance(n, ast.FunctionDef) and not n.name.startswith("__")}
        actual = {m for m in dir(getattr(hovs, name)) if not m.startswith("_")}
        if name != "Error":
            assert members == actual, name


def test_version_and_versions():
    v = hovs.versions()
    assert hovs.__version__ == v["hovs"] and "eigen" in v
