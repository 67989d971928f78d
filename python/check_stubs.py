"""Python.stubs: the type stubs (dpc31/__init__.pyi) name exactly what the native module binds.

Every class and function of the stubs exists in dpc31._dpc31 (or in dpc31 itself) and has every
member the stubs give it; every public name of the module and of its classes is in the stubs;
every method's parameters and their defaults are the binding's (`...`: any default).
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


def stub_params(fn):
    """(name, default) of a stub function's parameters after self; `*name` keyword-only; a
    default `...` stands for any."""
    a = fn.args
    plain = a.posonlyargs + a.args
    defaults = [None] * (len(plain) - len(a.defaults)) + [ast.unparse(d) for d in a.defaults]
    out = list(zip([x.arg for x in plain], defaults))
    out += [("*" + x.arg, None if d is None else ast.unparse(d))
            for x, d in zip(a.kwonlyargs, a.kw_defaults)]
    return [p for p in out if p[0] not in ("self", "cls")]


def split_top(text):
    """`text` split at the commas outside brackets."""
    parts, depth, cur = [], 0, ""
    for ch in text:
        depth += ch in "([{"
        depth -= ch in ")]}"
        if ch == "," and depth == 0:
            parts.append(cur.strip())
            cur = ""
        else:
            cur += ch
    return parts + [cur.strip()] if cur.strip() else parts


def native_params(obj):
    """(name, default) of each pybind11 signature in obj's docstring (one per overload)."""
    sigs = []
    for line in (getattr(obj, "__doc__", None) or "").splitlines():
        line = line.strip()
        head = line.split(". ", 1)[1] if line[:1].isdigit() and ". " in line else line
        if "(" not in head or ") -> " not in head:
            continue
        inner = head[head.index("(") + 1:head.rindex(") -> ")]
        params, kw_only = [], False
        for p in split_top(inner):
            if p == "*":
                kw_only = True
                continue
            name, _, default = p.partition("=")
            name = name.split(":")[0].strip()
            if name not in ("self", "cls"):
                params.append(("*" + name if kw_only else name, default.strip() or None))
        sigs.append(params)
    return sigs


def compare_signature(qual, fn, native):
    """The stub's parameters and defaults are one of the native signatures' (Python.stubs let
    `check_bus(slot_bits: int = 100)` stand where the binding's default is None)."""
    sigs = native_params(native)
    stub = stub_params(fn)
    if not sigs:
        return
    for sig in sigs:
        if any(n.startswith("**") for n, _ in sig):
            return  # the binding takes keywords of its own (SlaveConfig(**kwargs))
        if [n for n, _ in sig] == [n for n, _ in stub] and all(
                s == "..." or s == n for (_, s), (_, n) in zip(stub, sig)):
            return
    problems.append(f"{qual}{[f'{n}={d}' if d else n for n, d in stub]}: the module binds "
                    f"{[[f'{n}={d}' if d else n for n, d in sig] for sig in sigs]}")


for node in stubs.body:
    if isinstance(node, ast.ClassDef) and hasattr(_dpc31, node.name):
        for item in node.body:
            if isinstance(item, ast.FunctionDef) and not item.decorator_list and hasattr(
                    getattr(_dpc31, node.name), item.name):
                compare_signature(f"{node.name}.{item.name}", item,
                                  getattr(getattr(_dpc31, node.name), item.name))
    elif isinstance(node, ast.FunctionDef) and hasattr(dpc31, node.name):
        compare_signature(node.name, node, getattr(dpc31, node.name))

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
