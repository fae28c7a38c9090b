"""Every front end exposes exactly the compiled parameter tables (core/parameter_table.h): the
Python keywords, the CLI's options and the FreeCAD add-on's properties are built from the rows
the module exports, with their names, defaults and ranges."""

from __future__ import annotations

import argparse
import inspect
import math
import sys

import pytest

import hexmerge
from hexmerge import _core, _shape, _validate, cli
from conftest import ROOT

with_occ = pytest.mark.skipif(not _core.with_opencascade, reason="built without OpenCASCADE")

# The add-on's own properties and the CLI's own options of `mesh`: not parameters of a table.
# The add-on's own: the input, how pyramids reach FreeCAD, the order, the CalculiX element types.
ADDON_PROPERTIES = {"SourceMesh", "PyramidsAsHexahedra", "SecondOrder", "LinearHexahedron",
                    "QuadraticHexahedron", "QuadraticPyramid"}


def tables() -> list[tuple[str, list[dict]]]:
    out = [("engine", hexmerge.parameters())]
    if _core.with_opencascade:
        out.append(("mesher", hexmerge.mesh_parameters()))
    return out


def group_options(parser: argparse.ArgumentParser, title_start: str) -> dict[str, list[str]]:
    """{dest: option strings} of the argument group whose title starts so."""
    (group,) = [g for g in parser._action_groups if (g.title or "").startswith(title_start)]
    return {a.dest: list(a.option_strings) for a in group._group_actions}


def subparser(name: str) -> argparse.ArgumentParser:
    parser = cli.build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return sub.choices[name]


@pytest.mark.parametrize("which", ["engine", "mesher"])
def test_rows_are_complete_and_consistent(which) -> None:
    rows = dict(tables()).get(which)
    if rows is None:
        pytest.skip("built without OpenCASCADE")
    names = [r["name"] for r in rows]
    assert len(set(names)) == len(names)
    assert len({r["cli_flag"] for r in rows}) == len(rows)
    properties = [r["freecad_property"] for r in rows if r["freecad_property"]]
    assert len(set(properties)) == len(properties)
    for r in rows:
        assert r["type"] in ("float", "int", "bool", "choice", "text"), r["name"]
        assert r["doc"] and r["label"] and r["cli_flag"].startswith("--"), r["name"]
        if r["type"] in ("float", "int"):
            assert r["min"] < r["max"], r["name"]
            inside = r["min"] < r["default"] if r["min_exclusive"] else r["min"] <= r["default"]
            # The size has no default (0, outside its range): the user gives it.
            assert (inside and r["default"] <= r["max"]) or r["name"] == "size", r["name"]
        if r["type"] == "choice":
            assert r["default"] in r["choices"], r["name"]


def test_engine_and_mesher_names_do_not_overlap() -> None:
    """mesh_shape() takes both as keywords, told apart by name."""
    if not _core.with_opencascade:
        pytest.skip("built without OpenCASCADE")
    engine = {r["name"] for r in hexmerge.parameters()}
    mesher = {r["name"] for r in hexmerge.mesh_parameters()}
    assert not engine & mesher
    assert not {r["cli_flag"] for r in hexmerge.parameters()} & {r["cli_flag"] for r in hexmerge.mesh_parameters()}


def test_cli_recombine_options_are_the_engine_table() -> None:
    options = group_options(subparser("recombine"), "engine parameters")
    rows = hexmerge.parameters()
    assert list(options) == [r["name"] for r in rows]
    for r in rows:
        flags = [r["cli_flag"]] + (["--no-" + r["cli_flag"][2:]] if r["type"] == "bool" else [])
        assert options[r["name"]] == flags


@with_occ
def test_cli_mesh_options_are_both_tables() -> None:
    parser = subparser("mesh")
    mesher = group_options(parser, "mesher options")
    rows = hexmerge.mesh_parameters()
    assert list(mesher) == [r["name"] for r in rows]
    for r in rows:
        extra = ["-h"] if r["name"] == "size" else []
        flags = extra + [r["cli_flag"]] + (["--no-" + r["cli_flag"][2:]] if r["type"] == "bool" else [])
        assert mesher[r["name"]] == flags
    assert list(group_options(parser, "engine parameters")) == [r["name"] for r in hexmerge.parameters()]


def same_values(rows: list[dict], texts: dict[str, str]) -> dict[str, str]:
    """texts, where each equals its row's default_text as the value it stands for (150.0 is
    150); else the row's default_text."""
    out = {}
    for r in rows:
        text = texts.get(r["name"])
        numeric = r["type"] in ("float", "int") and text is not None
        out[r["name"]] = text if (numeric and float(text) == float(r["default_text"])) else r["default_text"]
    return out


def test_python_keywords_are_the_tables() -> None:
    """recombine() and mesh_shape() name no option themselves: every row is accepted by name,
    with its default, and a name outside the tables is refused."""
    rec = inspect.signature(hexmerge.recombine).parameters
    assert [p.kind for p in rec.values()][-1] == inspect.Parameter.VAR_KEYWORD
    assert not {r["name"] for r in hexmerge.parameters()} & set(rec)
    texts = _validate.options_text({r["name"]: r["default"] for r in hexmerge.parameters()})
    assert texts == same_values(hexmerge.parameters(), texts)
    with pytest.raises(ValueError, match="unknown option 'no_such_option'"):
        _validate.options_text({"no_such_option": 1})
    shape = inspect.signature(hexmerge.mesh_shape).parameters
    assert list(shape) == ["shape", "size", "second_order", "recombine", "progress", "options"]
    if _core.with_opencascade:
        rows = [r for r in hexmerge.mesh_parameters() if r["name"] != "size"]
        defaults = {r["name"]: r["default"] for r in rows}
        texts = _shape._options(4.0, defaults)
        assert texts.pop("size") == "4.0"
        assert texts == same_values(rows, texts)


@with_occ
@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        # The Python table said [0.001, 0.5], the C++ check (0, 0.5]: the one table says the first.
        ("surface_deflection", "0.0005", r"parameter 'surface_deflection' must be between 0.001 and 0.5 h"),
        ("surface_deflection", "0.6", r"must be between 0.001 and 0.5 h"),
        ("boundary_layers", "4", r"parameter 'boundary_layers' must be between -1 and 3"),
        ("boundary_layers", "1.5", r"must be a whole number"),
        ("frame", "diagonal", r"must be one of auto, principal, global"),
        ("size", "0", r"parameter 'size' must be greater than 0 mm"),
        ("size", "inf", r"parameter 'size' must be greater than 0 mm"),
        ("tetgen", "", r"parameter 'tetgen' must name the TetGen program"),
        ("local_sizes", "5-2", r"parameter 'local_sizes': entry '5-2' is not ITEMS:SIZE"),
        ("local_sizes", "Face5:x", r"parameter 'local_sizes': entry 'Face5:x' has size 'x'"),
        ("face_layers", "5:2", r"parameter 'face_layers': entry '5:2' is not FACES:LAYERS:THICKNESS"),
        ("face_layers", "5:2:x", r"parameter 'face_layers': entry '5:2:x' has thickness 'x'"),
        ("no_such_option", "1", r"unknown parameter 'no_such_option' \(the parameters are: size, "),
    ],
)
def test_mesher_table_checks_every_row(name, value, message) -> None:
    """The compiled mesher refuses a value outside its row before any work (no shape needed)."""
    options = {"size": "4", name: value}
    with pytest.raises(hexmerge.InputError, match=message) as info:
        _core.mesh_shape("no shape", options)
    assert info.value.entity == "parameter"


@with_occ
def test_mesher_table_bounds_are_inclusive_where_it_says() -> None:
    rows = {r["name"]: r for r in hexmerge.mesh_parameters()}
    deflection = rows["surface_deflection"]
    assert (deflection["min"], deflection["max"], deflection["min_exclusive"]) == (0.001, 0.5, False)
    # Both ends of a closed range pass the table (the shape is then refused, not the option).
    for value in ("0.001", "0.5"):
        with pytest.raises(hexmerge.InputError, match="BREP|shape") as info:
            _core.mesh_shape("no shape", {"size": "4", "surface_deflection": value})
        assert "surface_deflection" not in str(info.value)


def test_freecad_properties_are_the_tables() -> None:
    """The add-on's properties (built without FreeCAD from the same rows) are exactly the rows'
    freecad_property, plus the add-on's own."""
    sys.path.insert(0, str(ROOT))
    try:
        from freecad.hexmerge import properties
    finally:
        sys.path.remove(str(ROOT))
    specs = properties.all_specs()
    by_name = {s.name: s for s in specs}
    assert len(by_name) == len(specs)
    expected = {r["freecad_property"]: r for _, rows in tables() for r in rows if r["freecad_property"]}
    assert set(by_name) == set(expected) | ADDON_PROPERTIES
    for name, row in expected.items():
        spec = by_name[name]
        assert spec.parameter == row["name"]
        if row["type"] == "choice":
            assert spec.kind == "App::PropertyEnumeration" and list(spec.row["choices"]) == row["choices"]
        elif row["type"] == "float" and row["unit"] not in ("deg", "mm"):
            assert spec.kind == "App::PropertyFloatConstraint"
            assert (spec.row["min"], spec.row["max"]) == (row["min"], row["max"])
        if spec.kind != "App::PropertyEnumeration" and row["name"] not in ("pyramid_placement",):
            assert spec.default == row["default"] or math.isclose(spec.default, row["default"]), name
    # Rows the add-on does not show are the TetGen program and its work folder, and the local
    # sizes and face layers (from the analysis' mesh regions and boundary layer objects,
    # freecad/hexmerge/mesh_regions.py) only.
    hidden = {r["name"] for _, rows in tables() for r in rows if not r["freecad_property"]}
    assert hidden <= {"tetgen", "work_directory", "local_sizes", "face_layers"}
