"""meshio, imported on first use, with the gaps of Debian 12's meshio 5.0 filled in."""

from __future__ import annotations

from typing import Any


def meshio() -> Any:
    """The meshio module. meshio 5.0 knows the node counts and the VTK and Gmsh codes of
    wedge15 and pyramid13 but not their dimension, so it cannot even build a block of them;
    later versions list them, and then this changes nothing."""
    import meshio as module
    from meshio import _mesh

    for name in ("wedge15", "pyramid13"):
        _mesh.topological_dimension.setdefault(name, 3)
    return module


#: meshio format per extension where meshio's own guess is not the usual one (it takes ANSYS
#: for .msh).
PREFERRED_FORMAT = {".msh": "gmsh"}
