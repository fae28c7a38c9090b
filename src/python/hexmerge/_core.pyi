"""Types of the compiled module hexmerge._core (src/python/bindings.cpp)."""

from typing import Any, Callable, Literal, Mapping, overload

import numpy as np
import numpy.typing as npt

class InputError(ValueError):
    """Bad input: names the node or element at fault."""

    entity: str | None  # "node", "element", "parameter" or None
    index: int | None  # 0-based id of the node or element, or None

class Cancelled(Exception):
    """The run was cancelled from the progress callback."""

class ResourceError(MemoryError):
    """The machine cannot give the run what it needs (threads, memory)."""

def recombine(
    points: npt.NDArray[np.float64],
    cells: npt.NDArray[np.uint32],
    regions: npt.NDArray[np.int32] | None = None,
    options: Mapping[str, str] = ...,
    progress: Callable[[str, float], bool | None] | None = None,
) -> tuple[dict[str, Any], dict[str, Any]]: ...
def check_mesh(
    points: npt.NDArray[np.float64],
    types: npt.NDArray[np.uint8],
    offsets: npt.NDArray[np.uint32],
    cell_vertices: npt.NDArray[np.uint32],
    regions: npt.NDArray[np.int32] | None,
    source_offsets: npt.NDArray[np.uint32] | None,
    source_tets: npt.NDArray[np.uint32] | None,
    input_points: npt.NDArray[np.float64],
    input_tets: npt.NDArray[np.uint32],
    input_regions: npt.NDArray[np.int32] | None,
    changed_nodes: npt.NDArray[np.uint32] | None = None,
) -> dict[str, Any]: ...
def validate_tet_mesh(
    points: npt.NDArray[np.float64],
    cells: npt.NDArray[np.uint32],
    regions: npt.NDArray[np.int32] | None = None,
) -> None: ...
def parameter_table() -> list[dict[str, Any]]: ...
def tetrahedralize(
    points: npt.NDArray[np.float64],
    triangles: npt.NDArray[np.uint32],
    first_isolated: int = 0,
    tetgen: str = "tetgen",
    time_limit: float = 0.0,
    restarts: int = 5,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.uint32], str]: ...
def cell_types() -> list[dict[str, Any]]: ...

# Present only in a module built with OpenCASCADE (with_opencascade is True).
with_opencascade: bool

def regions_by_solid(
    brep: str,
    points: npt.NDArray[np.float64],
    cells: npt.NDArray[np.uint32],
    tolerance: float = 1e-6,
    samples_per_piece: int = 5,
    classify_every_tet: bool = False,
    nb_threads: int = 0,
) -> tuple[npt.NDArray[np.int32], dict[str, Any]]: ...
def mesh_shape(
    brep: str,
    options: Mapping[str, str],
    second_order: bool = False,
    progress: Callable[[str, float], bool | None] | None = None,
) -> tuple[
    npt.NDArray[np.float64], npt.NDArray[np.uint32], npt.NDArray[np.int32], dict[str, Any]
]: ...
def mesh_parameter_table() -> list[dict[str, Any]]: ...
@overload
def read_shape_file(path: str, with_unit: Literal[False] = False) -> str: ...
@overload
def read_shape_file(path: str, with_unit: Literal[True]) -> tuple[str, str]: ...
