"""The public entry points say what they take and what they give: each has an ``Args:`` section
that names every parameter of its signature (a class: every field) and a ``Returns:`` section.
Read from the source (no module is imported: rendering and MuJoCo stay unloaded)."""
import ast
import importlib.util
import re

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


def _definition(dotted: str):
    module, name = dotted.rsplit(".", 1)
    spec = importlib.util.find_spec(module)
    assert spec is not None and spec.origin, f"{module} not found"
    tree = ast.parse(open(spec.origin, encoding="utf-8").read())
    (node,) = [n for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef)) and n.name == name]
    return node


def parameters(node) -> list[str]:
    """A function's parameters (but ``self``), or a class's fields (annotated names of its body)."""
    if isinstance(node, ast.ClassDef):
        return [st.target.id for st in node.body if isinstance(st, ast.AnnAssign) and isinstance(st.target, ast.Name)]
    a = node.args
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


@pytest.mark.parametrize("dotted", ENTRY_POINTS)
def test_the_entry_point_has_args_and_returns(dotted):
    node = _definition(dotted)
    doc = ast.get_docstring(node) or ""
    s = sections(doc)
    assert "Args" in s and "Returns" in s, f"{dotted}: needs Args: and Returns: sections"
    assert s["Returns"].strip(), f"{dotted}: an empty Returns section"
    missing = [p for p in parameters(node) if p not in documented(s["Args"])]
    assert not missing, f"{dotted}: Args does not describe {missing}"
    extra = documented(s["Args"]) - set(parameters(node))
    assert not extra, f"{dotted}: Args describes what it does not take: {extra}"


def test_the_reader_sees_a_missing_parameter():
    node = ast.parse('def f(a, *, b):\n    """X.\n\n    Args:\n        a: one.\n\n    Returns:\n        x.\n    """\n').body[0]
    s = sections(ast.get_docstring(node))
    assert documented(s["Args"]) == {"a"} and parameters(node) == ["a", "b"]
    assert documented("        a, b: both.\n        c (int): one.\n            more: not a name.\n") == {"a", "b", "c"}
