"""The public entry points say what they take and what they give: each has an ``Args:`` section
that names every parameter of its signature (a class: its ``__init__``'s, a Protocol its
``__call__``'s, else every field), a ``Returns:`` section, and a ``Raises:`` section where its body
raises one of nbst's errors itself. The entry points are the list below and every function and
class that the packages nbst, nbst.search, nbst.sim, nbst.solvers and nbst.models.mjsearch export
(their ``__all__``), but the error classes (the family is documented in ``nbst.errors``) and
enumerations. Read from the source (no module is imported: rendering and MuJoCo stay unloaded)."""
import ast
import builtins
import importlib.util
import re
from pathlib import Path

import pytest

#: The public entry points, by the module that defines them (public aliases in the comments).
ENTRY_POINTS = [
    "nbst.search.api.solve",                  # nbst.search.solve
    "nbst.sim.api.simulate",                  # nbst.simulate, nbst.sim.simulate
    "nbst.sim.api.evaluate",                  # nbst.evaluate, nbst.sim.evaluate
    "nbst.problem.load_problem",              # nbst.load_problem
    "nbst.problem.Problem",                   # nbst.Problem
    "nbst.solution.load_solution",            # nbst.load_solution
    "nbst.solution.save_solution",            # nbst.save_solution
    "nbst.models.scene.scene_xml",            # nbst.models.scene_xml: nbst mjcf's export
    "nbst.render.core.video.render_video",    # nbst.render.render_video
    "nbst.render.crash.video.render_crash",   # nbst.render.render_crash
    "nbst.render.bowling.lane.render_throw",  # nbst.render.render_throw
    "nbst.render.bowling.deck.render_motion", # nbst.render.render_motion
    "nbst.models.crash.search.solve",         # nbst.models.crash.solve
    "nbst.models.crash.reconstruct.reconstruct",  # nbst.models.crash.reconstruct
    "nbst.models.bowling.lane.phases.throw",  # nbst.models.bowling.lane.throw
    "nbst.models.bowling.lane.frame.run_frame",
    "nbst.models.bowling.deck.search.solve",
]

#: The packages whose every exported function and class is an entry point.
EXPORTING = ("nbst", "nbst.search", "nbst.sim", "nbst.solvers", "nbst.models.mjsearch")


def _tree(module: str) -> ast.Module:
    spec = importlib.util.find_spec(module)
    assert spec is not None and spec.origin, f"{module} not found"
    return ast.parse(Path(spec.origin).read_text(encoding="utf-8"))


def _package_of(module: str) -> str:
    spec = importlib.util.find_spec(module)
    return module if spec.submodule_search_locations else module.rsplit(".", 1)[0]


def _lazy(module: str) -> dict[str, str]:
    """A package's lazy table (``_LAZY``/``_HOMES``: name -> module or submodule), as dotted modules."""
    out, pkg = {}, _package_of(module)
    for node in _tree(module).body:
        if isinstance(node, ast.Assign) and isinstance(node.value, ast.Dict) and any(
                isinstance(t, ast.Name) and t.id in ("_LAZY", "_HOMES") for t in node.targets):
            for k, v in zip(node.value.keys, node.value.values):
                if isinstance(k, ast.Constant) and isinstance(v, ast.Constant):
                    out[k.value] = v.value if v.value.startswith("nbst") else f"{pkg}.{v.value}"
    return out


def _homes(module: str) -> dict[str, str]:
    """Where each name ``module`` imports or lazily loads lives: ``from X import a`` (also under
    ``if TYPE_CHECKING``) and the lazy tables (``_LAZY``/``_HOMES``: name -> module or submodule)."""
    out = {}
    for node in ast.walk(_tree(module)):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("nbst") and node.level == 0:
            for a in node.names:
                out[a.asname or a.name] = node.module
    return {**out, **_lazy(module)}


def _exported(package: str) -> list[str]:
    """The names of ``package``'s ``__all__`` (a literal list, or ``sorted(_HOMES)``)."""
    tree = _tree(package)
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
            if isinstance(node.value, ast.List):
                return [e.value for e in node.value.elts if isinstance(e, ast.Constant)]
            return sorted(_lazy(package))
    return []


def _resolve(module: str, name: str, depth: int = 0) -> str | None:
    """The dotted name of the def or class ``module.name`` is (through re-exports), or None
    where it is something else (a constant, a module)."""
    for node in _tree(module).body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and node.name == name:
            return f"{module}.{name}"
    home = _homes(module).get(name)
    if home is None or depth > 4 or importlib.util.find_spec(home) is None:
        return None
    return _resolve(home, name, depth + 1)


def _is_error_or_enum(node) -> bool:
    bases = {ast.unparse(b).rsplit(".", 1)[-1] for b in getattr(node, "bases", [])}
    return node.name.endswith("Error") or bool(bases & {"Enum", "IntEnum", "Exception"})


def exported_entry_points() -> list[str]:
    out = []
    for package in EXPORTING:
        for name in _exported(package):
            dotted = _resolve(package, name)
            if dotted and dotted not in out and dotted not in ENTRY_POINTS:
                if not _is_error_or_enum(_definition(dotted)):
                    out.append(dotted)
    return out


def _definition(dotted: str):
    module, name = dotted.rsplit(".", 1)
    spec = importlib.util.find_spec(module)
    assert spec is not None and spec.origin, f"{module} not found"
    tree = ast.parse(open(spec.origin, encoding="utf-8").read())
    (node,) = [n for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef)) and n.name == name]
    return node


def _method(node, name: str):
    return next((st for st in node.body if isinstance(st, ast.FunctionDef) and st.name == name), None)


def _signature_node(node):
    """The node whose parameters a caller passes: a function itself, a class's ``__init__``, a
    Protocol's ``__call__``; None for a class built from its fields."""
    if not isinstance(node, ast.ClassDef):
        return node
    init = _method(node, "__init__")
    if init is not None:
        return init
    if any(ast.unparse(b).endswith("Protocol") for b in node.bases):
        return _method(node, "__call__")
    return None


def parameters(node) -> list[str]:
    """A function's parameters (but ``self``); a class's ``__init__``'s (a Protocol: its
    ``__call__``'s), else its fields (annotated names of its body)."""
    sig = _signature_node(node)
    if sig is None:
        return [st.target.id for st in node.body if isinstance(st, ast.AnnAssign) and isinstance(st.target, ast.Name)]
    a = sig.args
    return [p.arg for p in [*a.posonlyargs, *a.args, *a.kwonlyargs] if p.arg != "self"]


def sections(doc: str) -> dict[str, str]:
    """The docstring's Google-style sections: heading -> its indented text."""
    out, head = {}, None
    for line in doc.splitlines():
        m = re.match(r"^(Args|Returns|Raises|Yields|Attributes):\s*$", line)
        if m:
            head = m.group(1)
            out[head] = ""
        elif head and (line.startswith(" ") or not line.strip()):
            out[head] += line + "\n"
        else:
            head = None
    return out


def documented(args_section: str) -> set[str]:
    """The names an Args section describes (``name: ...`` or ``a, b: ...`` at its first indentation)."""
    lines = [ln for ln in args_section.splitlines() if ln.strip()]
    if not lines:
        return set()
    indent = min(len(ln) - len(ln.lstrip()) for ln in lines)
    return {name for ln in lines if len(ln) - len(ln.lstrip()) == indent
            for m in [re.match(r"\s*(\w+(?:, \w+)*)( \([^)]*\))?:", ln)] if m for name in m.group(1).split(", ")}


def raises_family(node) -> list[str]:
    """The errors a function's own body raises (not its nested functions'), by name: any raised
    name ending in ``Error`` that is not one of Python's (nbst raises only its family)."""
    body = _signature_node(node) if isinstance(node, ast.ClassDef) else node
    if body is None:
        return []
    found, todo = [], list(ast.iter_child_nodes(body))
    while todo:
        n = todo.pop()
        if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            continue
        if isinstance(n, ast.Raise) and n.exc is not None:
            exc = n.exc.func if isinstance(n.exc, ast.Call) else n.exc
            name = ast.unparse(exc).rsplit(".", 1)[-1]
            if name.endswith("Error") and not hasattr(builtins, name):
                found.append(name)
        todo.extend(ast.iter_child_nodes(n))
    return sorted(set(found))


def test_the_exported_entry_points_are_found():
    found = exported_entry_points()
    assert {"nbst.search.api.run_search", "nbst.sim.api.Trajectory", "nbst.solvers.dispatch.run_solver",
            "nbst.models.mjsearch.runner.Runner", "nbst.models.mjsearch.archive.grow"} <= set(found), found
    assert "nbst.errors.InputError" not in found and "nbst.search.params.StopReason" not in found


@pytest.mark.parametrize("dotted", ENTRY_POINTS + exported_entry_points())
def test_the_entry_point_has_args_and_returns(dotted):
    node = _definition(dotted)
    doc = ast.get_docstring(node) or ""
    s = sections(doc)
    raised = raises_family(node)
    assert not raised or "Raises" in s, f"{dotted}: raises {raised}; needs a Raises: section"
    assert "Args" in s and "Returns" in s, f"{dotted}: needs Args: and Returns: sections"
    assert s["Returns"].strip(), f"{dotted}: an empty Returns section"
    missing = [p for p in parameters(node) if p not in documented(s["Args"])]
    assert not missing, f"{dotted}: Args does not describe {missing}"
    extra = documented(s["Args"]) - set(parameters(node))
    assert not extra, f"{dotted}: Args describes what it does not take: {extra}"


def test_the_reader_sees_a_raise_of_the_family():
    node = ast.parse("def f(a):\n    if a:\n        raise InputError('x')\n    def g():\n        raise SolveError('y')\n"
                     "    raise ValueError('z')\n").body[0]
    assert raises_family(node) == ["InputError"]


def test_the_reader_sees_a_missing_parameter():
    node = ast.parse('def f(a, *, b):\n    """X.\n\n    Args:\n        a: one.\n\n    Returns:\n        x.\n    """\n').body[0]
    s = sections(ast.get_docstring(node))
    assert documented(s["Args"]) == {"a"} and parameters(node) == ["a", "b"]
    assert documented("        a, b: both.\n        c (int): one.\n            more: not a name.\n") == {"a", "b", "c"}
