"""docs/architecture.md's map of the layers is the contract's (pyproject.toml's
[tool.importlinter]): the diagram under "The layers" lists the rooms of the ``layers`` contract in
its order, and the table of inner layers has one row per inner ``layers`` contract, with the same
modules in the same order. A change to either fails here until the other follows."""
import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "architecture.md"
#: The rooms whose modules are layered inside (a container of a ``layers`` contract each).
INNER = {"nbst.sim", "nbst.search", "nbst.solvers", "nbst.models.bowling", "nbst.models.bowling.deck",
         "nbst.models.bowling.lane", "nbst.models.crash", "nbst.models.mjsearch", "nbst.render"}


def _contracts() -> list[dict]:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]["contracts"]


def _layers(layers: list[str]) -> list[set[str]]:
    return [{m.strip() for m in layer.split("|")} for layer in layers]


def doc_rooms() -> list[set[str]]:
    """The diagram's layers, top first: its unindented lines, up to the description column."""
    text = DOC.read_text(encoding="utf-8")
    block = text.split("## The layers", 1)[1].split("```", 2)[1]
    return [{m.strip() for m in line.split("  ")[0].split("|")} for line in block.splitlines()
            if line.startswith("nbst.")]


def doc_inner() -> dict[str, list[set[str]]]:
    """The table of inner layers: room -> its layers, top first (remarks in parentheses dropped)."""
    out = {}
    for line in DOC.read_text(encoding="utf-8").splitlines():
        m = re.match(r"\| `(nbst[\w.]*)` \| (.*) \|$", line)
        if not m:
            continue
        cell = m.group(2)
        while re.search(r"\([^()]*\)", cell):
            cell = re.sub(r"\([^()]*\)", "", cell)
        out[m.group(1)] = [set(re.findall(r"`(\w+)`", layer)) for layer in cell.split("→")]
    return out


def test_the_diagram_lists_the_contracts_rooms_in_its_order():
    (top,) = [c for c in _contracts() if c["id"] == "layers"]
    doc, contract = doc_rooms(), _layers(top["layers"])
    assert sum(map(len, doc)) >= 20  # 2026-12-03: 27 rooms in 14 layers
    assert set().union(*doc) == set().union(*contract), "rooms in one and not the other"
    assert doc == contract, "the layers differ in grouping or order"


def test_the_table_has_one_row_per_inner_contract_with_its_layers():
    contracts = {c["containers"][0]: _layers(c["layers"]) for c in _contracts()
                 if c["type"] == "layers" and c.get("containers")}
    table = doc_inner()
    assert set(contracts) == set(table), "rooms in one and not the other"
    for room, layers in contracts.items():
        assert set().union(*table[room]) == set().union(*layers), f"{room}: modules in one and not the other"
        assert table[room] == layers, f"{room}: the layers differ in grouping or order"


def test_the_rooms_with_inner_layers_all_have_a_contract():
    """The search, the simulator, the solvers, bowling and its halves, the crash, the rollout room
    and render are each layered module by module (tests/test_architecture.py checks that such a
    contract lists every module of its room)."""
    contained = {c["containers"][0] for c in _contracts() if c.get("containers")}
    assert INNER <= contained, INNER - contained


def test_the_parsers_read_what_is_written():
    rooms = doc_rooms()
    assert rooms[0] == {"nbst.cli"} and rooms[-1] == {"nbst.errors"}
    inner = doc_inner()
    assert inner["nbst.solvers"] == [{"islands"}, {"dispatch"}, {"baselines"}]  # "(`SOLVERS`, ...)" dropped
    assert {"polish", "planner"} in inner["nbst.search"]
