"""src/python/install.sh: a .pth file and a `hexmerge` wrapper, idempotent."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from conftest import PYTHON_SRC


def test_install_script_is_idempotent(tmp_path: Path) -> None:
    env = dict(os.environ, HEXMERGE_SITE_DIR=str(tmp_path / "site"), HEXMERGE_BIN_DIR=str(tmp_path / "bin"))
    for _ in range(2):
        subprocess.run(["sh", str(PYTHON_SRC / "install.sh")], env=env, check=True, capture_output=True)
    assert (tmp_path / "site" / "hexmerge.pth").read_text().strip() == str(PYTHON_SRC)
    wrapper = tmp_path / "bin" / "hexmerge"
    assert os.access(wrapper, os.X_OK)
    assert "/usr/bin/python3.11 -m hexmerge" in wrapper.read_text()
    assert sorted(p.name for p in (tmp_path / "bin").iterdir()) == ["hexmerge"]
    # The .pth file puts the checkout on the path of whoever reads that site folder (whatever
    # other installation the machine has: that is a question of path order, not of this file).
    code = (f"import site, sys; site.addsitedir({str(tmp_path / 'site')!r}); "
            f"print({str(PYTHON_SRC)!r} in sys.path)")
    done = subprocess.run([sys.executable, "-c", code], cwd="/", env={"PATH": os.environ["PATH"]}, capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "True"
    done = subprocess.run([str(wrapper), "--version"], env=dict(os.environ, PYTHONPATH=str(PYTHON_SRC)), capture_output=True, text=True, check=True)
    assert done.stdout.startswith("hexmerge ")
