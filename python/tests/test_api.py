"""The module's surface as a user meets it: every public attribute documented, and the type
stubs (pcr/_pcr.pyi) naming what the module has, no more and no less."""
import ast
import inspect
import os

import numpy as np
import pytest

import pcr

STUBS = os.path.join(os.path.dirname(pcr.__file__), "_pcr.pyi")
# Python's own members of every class, and pybind11's of an enumeration.
INHERITED = {"value", "name"}


def _public(names):
    return {n for n in names if not n.startswith("_")}


def _module_api():
    """{name: None for a function or constant, set of members for a class} of pcr._pcr."""
    api = {}
    for name in _public(dir(pcr._pcr)):
        obj = getattr(pcr._pcr, name)
        api[name] = _public(vars(obj)) - INHERITED if inspect.isclass(obj) else None
    return api


def _stub_api():
    tree = ast.parse(open(STUBS).read())
    api = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            members = set()
            for item in node.body:
                if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    members.add(item.name)
                elif isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name):
                    members.add(item.target.id)
                elif isinstance(item, ast.Assign):
                    members.update(t.id for t in item.targets if isinstance(t, ast.Name))
            api[node.name] = _public(members) - INHERITED
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            api[node.name] = None
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            api[node.target.id] = None
        elif isinstance(node, ast.Assign):
            for t in node.targets:
                if isinstance(t, ast.Name):
                    api[t.id] = None
    return {k: v for k, v in api.items() if not k.startswith("_")}


def test_stubs_name_what_the_module_has():
    module, stubs = _module_api(), _stub_api()
    # Aliases the stubs define for annotations only.
    stubs = {k: v for k, v in stubs.items() if k not in {"ArrayLike", "FloatArray", "StrPath",
                                                          "Vector"}}
    assert sorted(set(module) - set(stubs)) == [], "in the module, not in the stubs"
    if pcr.has_calibration and pcr.has_vision:  # the stubs describe the full build
        assert sorted(set(stubs) - set(module)) == [], "in the stubs, not in the module"
    # Members: the pure-Python additions of pcr/__init__.py are stubbed too.
    added = {"replace", "with_limb", "forward_batch", "inverse_batch"}
    for name, members in module.items():
        if members is None:
            continue
        missing = sorted(members - stubs.get(name, set()))
        extra = sorted(stubs.get(name, set()) - members - added)
        assert missing == [] and extra == [], f"{name}: not stubbed {missing}, not bound {extra}"


def test_every_public_attribute_is_documented():
    undocumented = []
    for name in _public(dir(pcr._pcr)):
        obj = getattr(pcr._pcr, name)
        if not inspect.isclass(obj):
            if callable(obj) and not (obj.__doc__ or "").split("\n", 1)[-1].strip():
                undocumented.append(name)
            continue
        for attr, value in vars(obj).items():
            if attr.startswith("_") or attr in INHERITED:
                continue
            if isinstance(value, property):
                doc = value.__doc__ or ""
            elif callable(value):
                # pybind11 puts the signature on the first line, the text after it.
                doc = (value.__doc__ or "").split("\n", 1)[-1]
            else:
                continue
            if not doc.strip():
                undocumented.append(f"{name}.{attr}")
    assert undocumented == []


def test_plots_without_matplotlib_say_how_to_get_it():
    # A fresh interpreter where matplotlib cannot be imported: pcr imports, pcr.plot names the
    # extra to install.
    import subprocess
    import sys
    code = ("import sys; sys.modules['matplotlib'] = None\n"
            "import pcr\n"
            "try:\n"
            "    import pcr.plot\n"
            "except ModuleNotFoundError as e:\n"
            "    print(e)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=dict(os.environ), check=True).stdout
    assert "pip install './python[plot]'" in out


def test_batch_methods_always_give_a_batch(robot):
    q = np.array([[0.001, 0.0, -0.001], [0.002, -0.001, 0.0]])
    batch = robot.forward_batch(q)
    assert isinstance(batch, pcr.BatchResult) and len(batch) == 2
    assert np.array_equal(batch.pose, robot.forward(q).pose)
    one = robot.forward_batch(q[:1])
    assert isinstance(one, pcr.BatchResult) and len(one) == 1
    back = robot.inverse_batch(batch.pose)
    assert isinstance(back, pcr.BatchResult) and np.allclose(back.q, q, atol=1e-9)
    with pytest.raises(ValueError, match=r"expected an \(N, n\) array.*shape \(3,\)"):
        robot.forward_batch(q[0])
    with pytest.raises(ValueError, match=r"expected an \(N, 3\) array"):
        robot.inverse_batch([0.0, 0.0, 0.0])
