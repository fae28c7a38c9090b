"""Files and values a user can get wrong end in one line naming the problem, never a traceback,
a wrong mesh or meshio's internals (issue 14, items 10, 15-18)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import hexmerge
from hexmerge import cli
from meshes import grid

meshio = pytest.importorskip("meshio")


def run(*args: object) -> int:
    return cli.main([str(a) for a in args])


def one_line_error(capsys, expected: str, *args: object) -> None:
    code = run(*args)
    err = capsys.readouterr().err
    assert code == 1, err
    assert len(err.strip().splitlines()) == 1 and err.startswith("hexmerge: error:"), err
    assert expected in err, err
    assert "Traceback" not in err


@pytest.fixture
def cube_files(tmp_path: Path) -> dict[str, Path]:
    points, tets, _ = grid(2, "five")
    mesh = meshio.Mesh(points, [("tetra", tets)])
    out = {}
    for suffix, kwargs in ((".vtk", {"binary": False}), (".inp", {}), (".msh", {"file_format": "gmsh22", "binary": False}),
                           (".mesh", {})):
        path = tmp_path / f"cube{suffix}"
        meshio.write(path, mesh, **kwargs)
        out[suffix] = path
    return out


@pytest.mark.parametrize("suffix", [".vtk", ".inp", ".msh", ".mesh"])
def test_a_file_cut_short_is_refused(tmp_path: Path, cube_files, capsys, suffix: str) -> None:
    """Cut inside the last cell line (for .inp: inside a node id, which read as another node),
    and for the formats that know their length, at the end of a line too."""
    data = cube_files[suffix].read_bytes()
    body = data.rstrip()
    cuts = {len(body) - 1}  # inside the last line
    if suffix in (".vtk", ".msh"):
        cuts.add(data.rstrip().rfind(b"\n", 0, len(body) - 40) + 1)  # at a line's start
    for cut in cuts:
        path = tmp_path / f"cut{cut}{suffix}"
        path.write_bytes(data[:cut])
        one_line_error(capsys, str(path), "recombine", path, "-o", tmp_path / "out.vtu")
        assert not (tmp_path / "out.vtu").exists()


def gmsh22(tags: list[int], tets: list[list[int]]) -> str:
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1.0]])
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$Nodes", str(len(tags))]
    lines += [f"{t} {p[0]} {p[1]} {p[2]}" for t, p in zip(tags, points)]
    lines += ["$EndNodes", "$Elements", str(len(tets))]
    lines += [f"{i + 1} 4 2 1 1 " + " ".join(map(str, q)) for i, q in enumerate(tets)]
    lines += ["$EndElements", ""]
    return "\n".join(lines)


def test_sparse_node_tags(tmp_path: Path, capsys) -> None:
    """Tags near 1e12 made meshio allocate 8 GB and then 'element 0 refers to node -1'."""
    tags = [1, 2, 3, 4, 10**12]
    path = tmp_path / "sparse.msh"
    path.write_text(gmsh22(tags, [[1, 2, 3, 4], [2, 3, 4, 10**12]]))
    one_line_error(capsys, "node tags are too sparse", "recombine", path, "-o", tmp_path / "out.vtu")
    # Sparse but moderate tags are read (and mapped) correctly.
    path.write_text(gmsh22([1, 2, 3, 4, 1000], [[1, 2, 3, 4], [2, 3, 4, 1000]]))
    assert run("recombine", path, "-o", tmp_path / "ok.vtu", "-q") == 0
    # An element naming a tag the file lacks is said plainly.
    path.write_text(gmsh22([1, 2, 3, 4, 5], [[1, 2, 3, 4], [2, 3, 999999, 4]]))
    code = run("recombine", path, "-o", tmp_path / "out.vtu")
    err = capsys.readouterr().err
    assert code == 1 and "Traceback" not in err and "KeyError" not in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize(
    "tags, expected",
    [
        ([1, 2, "2.5", 4, 5], "node tag 2.5 is not a whole number"),
        ([1, 2, "x3", 4, 5], "node tag x3 is not a whole number"),
        ([1, 2, 0, 4, 5], "node tag 0 is not positive"),
        ([1, -2, 3, 4, 5], "node tag -2 is not positive"),
        ([1, 2, 3, 4, 10**30], "node tags are too sparse to read (largest 1000000000000000000000000000000"),
        ([1, 2, "3\0", 4, 5], "node tag 3\0 is not a whole number"),
    ],
)
def test_bad_node_tags_are_named(tmp_path: Path, capsys, tags: list, expected: str) -> None:
    path = tmp_path / "tags.msh"
    path.write_text(gmsh22(tags, [[1, 2, 4, 5]]))
    one_line_error(capsys, expected, "recombine", path, "-o", tmp_path / "out.vtu")
    assert not (tmp_path / "out.vtu").exists()


def test_gmsh_section_not_closed(tmp_path: Path, capsys) -> None:
    text = gmsh22([1, 2, 3, 4, 5], [[1, 2, 3, 4]])
    path = tmp_path / "open.msh"
    path.write_text(text.replace("$EndElements\n", ""))
    one_line_error(capsys, "section $Elements is not closed", "recombine", path, "-o", tmp_path / "out.vtu")
    # With Windows line ends every section is still seen as closed.
    path.write_text(text.replace("\n", "\r\n"))
    assert run("recombine", path, "-o", tmp_path / "crlf.vtu", "-q") == 0


def test_meshio_internals_do_not_leak(tmp_path: Path, capsys) -> None:
    path = tmp_path / "nothing.msh"
    path.write_text("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n0\n$EndNodes\n$Elements\n0\n$EndElements\n")
    code = run("recombine", path, "-o", tmp_path / "out.vtu")
    err = capsys.readouterr().err
    assert code == 1 and len(err.strip().splitlines()) == 1, err
    assert "concatenate" not in err and "Traceback" not in err
    unknown = tmp_path / "mesh.unknownformat"
    unknown.write_text("x")
    one_line_error(capsys, "cannot read", "recombine", unknown, "-o", tmp_path / "out.vtu")


@pytest.mark.parametrize("name, value", [("threads", math.inf), ("threads", 10**400), ("min_dihedral_angle", 10**400),
                                         ("min_dihedral_angle", math.nan), ("local_search_nodes", -math.inf)])
def test_numbers_out_of_any_range_name_the_option(name: str, value) -> None:
    points, tets, _ = grid(1, "kuhn")
    with pytest.raises(ValueError, match=name):
        hexmerge.recombine(points, tets, **{name: value})


def test_a_progress_callback_returning_a_non_bool_is_named() -> None:
    points, tets, _ = grid(2, "kuhn")
    with pytest.raises(hexmerge.InputError, match="progress must return True, False or None"):
        hexmerge.recombine(points, tets, progress=lambda phase, fraction: "yes")
    hexmerge.recombine(points, tets, progress=lambda phase, fraction: np.bool_(True))


def test_check_reads_the_collapsed_pyramids_it_documents(tmp_path: Path, capsys, gmsh_tet4: Path) -> None:
    """`--collapse-pyramids` writes pyramids as degenerate hexahedra for CalculiX: `hexmerge check`
    reads them back as pyramids (it reported cracks and 'hex uses node twice')."""
    out = tmp_path / "out.inp"
    assert run("recombine", gmsh_tet4, "-o", out, "--collapse-pyramids", "-q") == 0
    assert any(b.type == "hexahedron" and (b.data[:, 4:] == b.data[:, 4:5]).all(axis=1).any() for b in meshio.read(out).cells)
    capsys.readouterr()
    assert run("check", out, "--source", gmsh_tet4) == 0, capsys.readouterr().out
    assert capsys.readouterr().out.strip().endswith("valid")


def test_work_directory_naming_a_file(tmp_path: Path, capsys) -> None:
    if not hexmerge.WITH_OPENCASCADE:
        pytest.skip("built without OpenCASCADE")
    step = tmp_path / "box.brep"
    a_file = tmp_path / "file.txt"
    a_file.write_text("x")
    step.write_text("not used")
    one_line_error(capsys, "not a folder", "mesh", step, "-h", "1", "-o", tmp_path / "o.vtu",
                   "--work-directory", a_file / "sub")


def test_threads_the_system_cannot_start_are_one_line(tmp_path: Path) -> None:
    """--threads 1024 (inside the documented range) under a 4 GB address-space limit: a thread
    fails to start; before, the process aborted (SIGABRT, exit 134, no message)."""
    import subprocess
    import sys

    from conftest import PYTHON_SRC

    points, tets, _ = grid(4, "kuhn")
    src = tmp_path / "in.vtu"
    meshio.write(src, meshio.Mesh(points, [("tetra", tets)]))
    script = (
        "import resource, sys\n"
        "resource.setrlimit(resource.RLIMIT_AS, (4 << 30, resource.RLIM_INFINITY))\n"
        "from hexmerge import cli\n"
        "sys.exit(cli.main(sys.argv[1:]))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script, "recombine", str(src), "-o", str(tmp_path / "out.vtu"), "--threads", "1024"],
        capture_output=True, text=True, env={"PYTHONPATH": str(PYTHON_SRC), "PATH": "/usr/bin:/bin"}, timeout=300,
    )
    assert done.returncode == 1, (done.returncode, done.stderr)
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert "could not start thread" in done.stderr and "threads" in done.stderr
    assert not (tmp_path / "out.vtu").exists()


def test_out_of_memory_is_one_line(tmp_path: Path, capsys, monkeypatch) -> None:
    points, tets, _ = grid(1, "kuhn")
    src = tmp_path / "in.vtu"
    meshio.write(src, meshio.Mesh(points, [("tetra", tets)]))

    def no_memory(*args, **kwargs):
        raise MemoryError("std::bad_alloc")

    monkeypatch.setattr(hexmerge._api, "recombine", no_memory)
    one_line_error(capsys, "out of memory", "recombine", src, "-o", tmp_path / "out.vtu")
