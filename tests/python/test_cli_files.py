"""The command line's files: it never overwrites its input, writes regular files only, writes
nothing unless the whole run succeeded, and refuses formats that cannot hold volume cells."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from hexmerge import cli
from meshes import grid

meshio = pytest.importorskip("meshio")


def run(*args: object) -> int:
    return cli.main([str(a) for a in args])


@pytest.fixture
def src(tmp_path: Path) -> Path:
    points, tets, _ = grid(2, "kuhn")
    path = tmp_path / "in.vtu"
    meshio.write(path, meshio.Mesh(points, [("tetra", tets)]))
    return path


def no_temp_files(folder: Path) -> bool:
    return [p.name for p in folder.iterdir() if p.name.startswith(".")] == []


def fails_with(capsys, expected: str, *args: object) -> None:
    code = run(*args)
    err = capsys.readouterr().err
    assert code == 1, err
    assert len(err.strip().splitlines()) == 1 and err.startswith("hexmerge: error:"), err
    assert expected in err, err


@pytest.mark.parametrize("spelling", ["same", "dotdot", "hardlink", "symlinked-folder"])
def test_output_naming_the_input_is_refused(tmp_path: Path, src: Path, capsys, spelling: str) -> None:
    before = src.read_bytes()
    out = {
        "same": src,
        "dotdot": tmp_path / "sub" / ".." / src.name,
        "hardlink": tmp_path / "link.vtu",
        "symlinked-folder": tmp_path / "alias" / src.name,
    }[spelling]
    (tmp_path / "sub").mkdir()
    if spelling == "hardlink":
        os.link(src, out)
    if spelling == "symlinked-folder":
        (tmp_path / "alias").symlink_to(tmp_path)
    fails_with(capsys, "is also the input", "recombine", src, "-o", out)
    assert src.read_bytes() == before


def test_stats_naming_the_input_or_the_output_is_refused(tmp_path: Path, src: Path, capsys) -> None:
    before = src.read_bytes()
    fails_with(capsys, "is also the input", "recombine", src, "-o", tmp_path / "out.vtu", "--stats", src)
    out = tmp_path / "out.vtu"
    fails_with(capsys, "is also the output", "recombine", src, "-o", out, "--stats", tmp_path / "." / "out.vtu")
    assert src.read_bytes() == before and not out.exists()


def test_symlink_fifo_and_device_are_refused(tmp_path: Path, src: Path, capsys) -> None:
    target = tmp_path / "target.vtu"
    target.write_text("kept")
    link = tmp_path / "link.vtu"
    link.symlink_to(target)
    fails_with(capsys, "symbolic link", "recombine", src, "-o", link)
    assert link.is_symlink() and target.read_text() == "kept"
    fifo = tmp_path / "pipe.vtu"
    os.mkfifo(fifo)
    fails_with(capsys, "FIFO", "recombine", src, "-o", fifo)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    fails_with(capsys, "character device", "recombine", src, "-o", "/dev/null", "--output-format", "vtu")
    assert stat.S_ISCHR(os.lstat("/dev/null").st_mode)
    fails_with(capsys, "character device", "recombine", src, "-o", tmp_path / "o.vtu", "--stats", "/dev/null")
    fails_with(capsys, "a folder", "recombine", src, "-o", tmp_path / "o.vtu", "--stats", tmp_path)
    assert not (tmp_path / "o.vtu").exists() and no_temp_files(tmp_path)


def test_a_failing_stats_file_leaves_no_output(tmp_path: Path, src: Path, capsys, monkeypatch) -> None:
    """The --stats file is written after the mesh: when it fails, the mesh is not left behind
    (and an earlier output stays as it was)."""
    out, stats = tmp_path / "out.vtu", tmp_path / "stats.json"
    out.write_text("previous result")
    real = Path.write_text

    def full_disk(self: Path, text: str, *args, **kwargs):
        if self.name.startswith(".stats."):
            raise OSError(28, "No space left on device")
        return real(self, text, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", full_disk)
    fails_with(capsys, "No space left on device", "recombine", src, "-o", out, "--stats", stats)
    assert out.read_text() == "previous result" and not stats.exists() and no_temp_files(tmp_path)
    monkeypatch.undo()
    assert run("recombine", src, "-o", out, "--stats", stats, "-q") == 0
    assert meshio.read(out).cells[0].type == "hexahedron" and stats.read_text().startswith("{")


@pytest.mark.parametrize("name, fmt", [("out.stl", None), ("out.obj", None), ("out.off", None),
                                       ("out.ply", None), ("out.vtu", "stl")])
def test_surface_only_formats_are_refused(tmp_path: Path, src: Path, capsys, name: str, fmt: str | None) -> None:
    out = tmp_path / name
    extra = ["--output-format", fmt] if fmt else []
    fails_with(capsys, "holds surfaces only", "recombine", src, "-o", out, *extra)
    assert not out.exists() and no_temp_files(tmp_path)
