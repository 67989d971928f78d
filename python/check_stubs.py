"""Python.stubs: the type stubs (dpc31/__init__.pyi) name exactly what the native module binds.

Every class and function of the stubs exists in dpc31._dpc31 (or in dpc31 itself) and has every
member the stubs give it; every public name of the module and of its classes is in the stubs.
Usage: python3 check_stubs.py STUBS (with the built package on PYTHONPATH)."""

import ast
import inspect
import sys

import dpc31
from dpc31 import _dpc31

stubs = ast.parse(open(sys.argv[1]).read())
problems = []
stub_names = set()
stub_classes = {node.name: node for node in stubs.body if isinstance(node, ast.ClassDef)}


def stub_members(node):
    """The members a stub class gives, with those of its stub base classes (MasterSlave's)."""
    members = set()
    for base in node.bases:
        if isinstance(base, ast.Name) and base.id in stub_classes:
            members |= stub_members(stub_classes[base.id])
    for item in node.body:
        if isinstance(item, (ast.FunctionDef,)):
            members.add(item.name)
        elif isinstance(item, ast.AnnAssign):
            members.add(item.target.id)
        elif isinstance(item, ast.Assign):
            members.update(t.id for t in item.targets)
    return members


for node in stubs.body:
    if isinstance(node, ast.ClassDef):
        stub_names.add(node.name)
        native = getattr(_dpc31, node.name, None)
        if native is None:
            problems.append(f"class {node.name}: not in the module")
            continue
        if issubclass(native, BaseException):
            continue  # their attributes (ScenarioError.file, ...) are set on each instance
        members = stub_members(node)
        for m in members:
            if not hasattr(native, m):
                problems.append(f"{node.name}.{m}: not in the module")
        enum_members = getattr(native, "__members__", None)
        for m, _ in inspect.getmembers(native):
            if m.startswith("_") or (enum_members is not None and
                                     (m in enum_members or m in ("name", "value"))):
                continue
            if m not in members:
                problems.append(f"{node.name}.{m}: bound but not in the stubs")
    elif isinstance(node, ast.FunctionDef):
        stub_names.add(node.name)
        if not hasattr(dpc31, node.name):
            problems.append(f"function {node.name}: not in the package")
for name in dir(_dpc31):
    if not name.startswith("_") and name not in stub_names:
        problems.append(f"{name}: bound but not in the stubs")
for name in dpc31.__all__:
    if name not in stub_names:
        problems.append(f"dpc31.__all__ names {name}, the stubs do not")
for p in problems:
    print(f"{sys.argv[1]}: {p}")
sys.exit(1 if problems else 0)
