"""Type stubs of the extension module atelier._atelier (python/src/*.cpp).

Arrays are numpy arrays; "view" means a read-only array onto the engine's
memory that keeps its owner alive (zero copy). docs/python.md describes
every call; the docstrings of the module repeat it (help(atelier.X)).
"""
from os import PathLike
from typing import Any, Callable, Iterator, Optional, Sequence, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

Path = Union[str, PathLike[str]]
FloatArray = npt.NDArray[np.floating[Any]]
IndexArray = npt.NDArray[np.integer[Any]]
#: (F, k) indices, or a list of polygons of any sizes.
Faces = Union[IndexArray, Sequence[Sequence[int]]]
#: progress(stage, done, total), called on the calling thread; raise to cancel.
Progress = Optional[Callable[[str, int, int], Any]]
DType = Union[str, type, np.dtype[Any]]
#: Mannequin parameters: one dict, a list of dicts, or a structured array.
Params = Union[None, dict[str, float], Sequence[dict[str, Any]], npt.NDArray[np.void]]

# ---------------------------------------------------------------- files

class Mesh:
    """A polygon mesh: vertices (n, 3) and polygon faces (immutable)."""

    def __init__(self, vertices: FloatArray, faces: Faces) -> None: ...
    @property
    def vertices(self) -> npt.NDArray[np.float64]:
        """(n, 3) float64 view."""
    @property
    def faces(self) -> Union[npt.NDArray[np.uint32], list[npt.NDArray[np.uint32]]]:
        """(F, k) uint32 view, or a list of arrays for mixed polygons."""
    @property
    def face_offsets(self) -> npt.NDArray[np.uint32]: ...
    @property
    def face_indices(self) -> npt.NDArray[np.uint32]: ...
    @property
    def triangles(self) -> npt.NDArray[np.uint32]:
        """(T, 3) fan triangles."""
    @property
    def vertex_count(self) -> int: ...
    @property
    def face_count(self) -> int: ...
    @property
    def surfaces(self) -> list[str]: ...
    @property
    def face_surface(self) -> npt.NDArray[np.int32]: ...
    def validate(self) -> None: ...
    def __iter__(self) -> Iterator[Any]: ...

MeshLike = Union[Mesh, "Body", tuple[FloatArray, Faces]]

def read_mesh(path: Path) -> Mesh:
    """OBJ, PLY, OFF or .atm; ``vertices, faces = read_mesh(path)``."""

def write_mesh(path: Path, mesh: Union[MeshLike, FloatArray], faces: Optional[Faces] = None, binary: bool = True) -> None:
    """Writes by extension, atomically; bit-exact round trips."""

def read_png(path: Path) -> npt.NDArray[np.uint8]:
    """(H, W, 3) RGB."""

def write_png(path: Path, image: npt.NDArray[np.uint8], level: int = 6) -> None: ...

# ---------------------------------------------------------------- bodies

class Body:
    """A reference body: closed skin with feature curves and points."""

    @staticmethod
    def from_arrays(vertices: FloatArray, faces: Faces) -> Body: ...
    @staticmethod
    def read(
        path: Path, *, scale: float = 1.0, up: str = "y", data: Optional[Path] = None, features: Optional[Path] = None
    ) -> Body: ...
    @property
    def vertices(self) -> npt.NDArray[np.float64]: ...
    @property
    def faces(self) -> Union[npt.NDArray[np.uint32], list[npt.NDArray[np.uint32]]]: ...
    @property
    def triangles(self) -> npt.NDArray[np.uint32]: ...
    @property
    def node_count(self) -> int: ...
    @property
    def mesh(self) -> Mesh: ...
    @property
    def curves(self) -> list[str]: ...
    @property
    def points(self) -> list[str]: ...
    def curve(self, name: Union[str, int], positions: Optional[FloatArray] = None) -> npt.NDArray[np.float64]: ...
    def measure(self, positions: Optional[FloatArray] = None) -> dict[str, float]: ...
    def measure_many(self, bodies: FloatArray, *, threads: int = 0, progress: Progress = None) -> npt.NDArray[np.void]: ...
    def with_positions(self, positions: FloatArray) -> Body: ...

def sample_mannequins(n: int, seed: int = 1) -> npt.NDArray[np.void]:
    """Structured array (n,) of mannequin parameters."""

def sample_mannequin(seed: int, index: int) -> dict[str, float]: ...
def mannequin_fields() -> list[str]: ...

class Mannequin:
    """The procedural mannequin at one resolution (one topology)."""

    def __init__(self, level: int = 6) -> None: ...
    @property
    def node_count(self) -> int: ...
    @property
    def faces(self) -> Union[npt.NDArray[np.uint32], list[npt.NDArray[np.uint32]]]: ...
    def reference(self, params: Optional[dict[str, float]] = None) -> Body: ...
    def positions(
        self, params: Params, *, dtype: DType = "float64", threads: int = 0, progress: Progress = None
    ) -> FloatArray:
        """(B, n, 3), or (n, 3) for one dict."""

class MakeHuman:
    """MakeHuman bodies from the shared data."""

    def __init__(self, path: Optional[Path] = None, *, threads: int = 0, progress: Progress = None) -> None: ...
    @property
    def node_count(self) -> int: ...
    @property
    def measure_modifiers(self) -> list[str]: ...
    def reference(self) -> Body: ...
    @staticmethod
    def sample(n: int, seed: int = 1) -> npt.NDArray[np.void]: ...
    def adults(self, n: int, seed: int = 1) -> tuple[npt.NDArray[np.void], FloatArray]: ...
    def positions(
        self, params: Params, *, dtype: DType = "float64", threads: int = 0, progress: Progress = None
    ) -> FloatArray: ...
    def garment(self, mhclo: Path) -> Mesh: ...

def skin_band_garment(
    body: Body, y_lo: float, y_hi: float, offset: float, max_radius: float, name: str = "band"
) -> Mesh: ...

# ---------------------------------------------------------------- garments

class GarmentFamily:
    """The reference body's polygons and collision topology."""

    def __init__(self, body: Body) -> None: ...
    @property
    def body(self) -> Body: ...
    @property
    def node_count(self) -> int: ...

class GarmentTemplate:
    """A garment encoded on a family (immutable)."""

    @property
    def name(self) -> str: ...
    @property
    def family(self) -> GarmentFamily: ...
    @property
    def z_depth(self) -> int: ...
    @property
    def vertex_count(self) -> int: ...
    @property
    def entries(self) -> int: ...
    @property
    def vertices(self) -> npt.NDArray[np.float64]: ...
    @property
    def faces(self) -> Union[npt.NDArray[np.uint32], list[npt.NDArray[np.uint32]]]: ...
    @property
    def edges(self) -> npt.NDArray[np.uint32]: ...
    @property
    def rest_length(self) -> npt.NDArray[np.float64]: ...
    @property
    def reference_clearance(self) -> npt.NDArray[np.float32]: ...
    @property
    def mesh(self) -> Mesh: ...
    def with_z_depth(self, z_depth: int) -> GarmentTemplate: ...
    def save(self, dir: Path) -> None: ...

@overload
def encode_garment(
    family: GarmentFamily,
    garment: FloatArray,
    faces: Faces,
    *,
    name: Optional[str] = None,
    edges: Optional[IndexArray] = None,
    z_depth: int = 0,
    polygons_per_vertex: int = 0,
    scaled_frames: bool = False,
    scale: float = 1.0,
    up: str = "y",
    threads: int = 0,
    progress: Progress = None,
) -> GarmentTemplate: ...
@overload
def encode_garment(
    family: GarmentFamily,
    garment: Union[Mesh, Path],
    faces: None = None,
    *,
    name: Optional[str] = None,
    edges: Optional[IndexArray] = None,
    z_depth: int = 0,
    polygons_per_vertex: int = 0,
    scaled_frames: bool = False,
    scale: float = 1.0,
    up: str = "y",
    threads: int = 0,
    progress: Progress = None,
) -> GarmentTemplate: ...
def read_garment_template(
    family: GarmentFamily, path: Path, *, z_depth: int = 0, threads: int = 0, progress: Progress = None
) -> GarmentTemplate: ...

class Regeneration:
    """Positions and fit figures of a batch."""

    @property
    def names(self) -> list[str]: ...
    @property
    def positions(self) -> list[FloatArray]:
        """Per garment (B, m, 3)."""
    @property
    def quality(self) -> list[npt.NDArray[np.void]]:
        """Per garment, structured (B,)."""
    @property
    def ok(self) -> npt.NDArray[np.bool_]: ...
    @property
    def errors(self) -> list[Optional[str]]: ...
    def __len__(self) -> int: ...

class Regenerator:
    """The reusable garment pipeline."""

    def __init__(
        self,
        garments: Union[GarmentTemplate, Sequence[GarmentTemplate]],
        *,
        layers: bool = True,
        edge_transfer: bool = True,
        collision_pass: bool = True,
        kernel: str = "auto",
    ) -> None: ...
    @property
    def garments(self) -> list[GarmentTemplate]: ...
    def run(
        self,
        bodies: FloatArray,
        *,
        threads: int = 0,
        progress: Progress = None,
        chunk: int = 256,
        dtype: DType = "float64",
        fit: bool = False,
    ) -> Regeneration: ...
    def run_one(self, body: FloatArray) -> list[tuple[npt.NDArray[np.float64], dict[str, Any]]]: ...

def regenerate(
    garments: Union[GarmentTemplate, Sequence[GarmentTemplate]],
    bodies: FloatArray,
    *,
    layers: bool = True,
    edge_transfer: bool = True,
    collision_pass: bool = True,
    threads: int = 0,
    progress: Progress = None,
    chunk: int = 256,
    dtype: DType = "float64",
    fit: bool = False,
) -> Regeneration:
    """Regenerates garments on a (B, n, 3) batch of bodies."""

def measure_fit(
    body: MeshLike,
    garment: MeshLike,
    *,
    source_garment: Optional[FloatArray] = None,
    source_body: Optional[FloatArray] = None,
    inside_tolerance: float = 0.001,
    threads: int = 0,
) -> dict[str, float]: ...

# ---------------------------------------------------------------- profile templates

class ProfileTemplate:
    """A profile template (feature nodes, surfaces, joints, profiles)."""

    @staticmethod
    def load(path: Path) -> ProfileTemplate: ...
    @staticmethod
    def from_json(text: str, name: str = "<memory>") -> ProfileTemplate: ...
    def to_json(self) -> str: ...
    def save(self, path: Path) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def reference(self) -> str: ...
    @property
    def levels(self) -> int: ...
    @property
    def clearance(self) -> float: ...
    @property
    def node_names(self) -> list[str]: ...
    @property
    def profile_count(self) -> int: ...
    @property
    def mesh(self) -> Mesh: ...

def read_profile_template(path: Path) -> ProfileTemplate: ...
def project_templates(body: Body) -> list[ProfileTemplate]: ...

class ProfileRegeneration:
    """Meshes and quality of regenerate_profiles."""

    @property
    def names(self) -> list[str]: ...
    @property
    def meshes(self) -> list[list[Optional[Mesh]]]: ...
    @property
    def quality(self) -> list[npt.NDArray[np.void]]: ...
    @property
    def ok(self) -> npt.NDArray[np.bool_]: ...
    @property
    def errors(self) -> list[Optional[str]]: ...
    def __len__(self) -> int: ...

def regenerate_profiles(
    templates: Union[ProfileTemplate, Sequence[ProfileTemplate]],
    reference: Body,
    bodies: FloatArray,
    *,
    levels: int = -1,
    clearance: float = -1.0,
    threads: int = 0,
    progress: Progress = None,
) -> ProfileRegeneration: ...

# ---------------------------------------------------------------- pictures

def render(
    body: Optional[MeshLike],
    garments: Union[None, MeshLike, Sequence[MeshLike]] = None,
    *,
    width: int = 480,
    height: int = 640,
    view: str = "front",
    projection: str = "orthographic",
    colours: Optional[Sequence[Sequence[float]]] = None,
    supersample: int = 1,
    outlines: bool = False,
    background: Optional[Sequence[float]] = None,
    path: Optional[Path] = None,
    threads: int = 0,
    progress: Progress = None,
) -> npt.NDArray[np.uint8]:
    """(H, W, 3) RGB picture; also a PNG at ``path``."""

# ---------------------------------------------------------------- modelling families

def boolean(
    a: Union[MeshLike, PreparedNet],
    b: Union[MeshLike, PreparedNet],
    *,
    op: str = "union",
    mode: str = "exact",
    correspondence: str = "visual",
    join: str = "cut",
    rule: str = "a",
    self_check: bool = True,
    exact_refinement: bool = False,
    prepare_result: bool = False,
    check_result: bool = False,
    threads: int = 0,
    progress: Progress = None,
) -> tuple[npt.NDArray[np.float64], Union[npt.NDArray[np.uint32], list[npt.NDArray[np.uint32]]], dict[str, Any]]:
    """Union, intersection or difference of two closed nets (meshes or PreparedNets): (vertices, faces, report)."""

class PreparedNet:
    """A closed net converted, checked and given its box hierarchy once, for many Booleans."""

    def __init__(self, net: MeshLike, *, self_check: bool = True, threads: int = 0, progress: Progress = None) -> None: ...
    @property
    def volume(self) -> float: ...
    @property
    def area(self) -> float: ...
    @property
    def triangles(self) -> int: ...
    @property
    def self_checked(self) -> bool: ...

def trim(
    net: MeshLike,
    curve: FloatArray,
    *,
    height: float = 0.0,
    keep_enclosed: bool = False,
    threads: int = 0,
    progress: Progress = None,
) -> tuple[npt.NDArray[np.float64], Union[npt.NDArray[np.uint32], list[npt.NDArray[np.uint32]]], dict[str, Any]]:
    """Trims a net by a closed curve on it: (vertices, faces, report)."""

def round_off(
    net: MeshLike,
    seam: IndexArray,
    *,
    mu: float = 1.0,
    nu: float = 1.0,
    rings: int = 1,
    threads: int = 0,
    progress: Progress = None,
) -> tuple[npt.NDArray[np.float64], Union[npt.NDArray[np.uint32], list[npt.NDArray[np.uint32]]], dict[str, Any]]:
    """Rounds off a seam by the umbrella energy: (vertices, faces, report)."""

def surface_from_curves(
    curves: Union[Path, Sequence[FloatArray]],
    *,
    levels: int = 2,
    mesh: Optional[MeshLike] = None,
    cycles: str = "angular",
    n0: int = 3,
    density: float = 0.0,
    tolerance: float = 1e-6,
    fairing: bool = True,
    threads: int = 0,
    progress: Progress = None,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.uint32], dict[str, Any]]:
    """A curve network to a Catmull-Clark surface through it: (vertices, faces, report)."""

def flatten(
    mesh: MeshLike,
    *,
    surfaces: Optional[Sequence[str]] = None,
    grain: Optional[FloatArray] = None,
    allow_holes: bool = False,
    free_seams: bool = False,
    threads: int = 0,
    progress: Progress = None,
) -> tuple[npt.NDArray[np.float64], list[dict[str, Any]]]:
    """Flattens the pieces into the plane: (uv (n, 2), pieces with distortion figures)."""

def made_to_measure_pattern(
    mesh: MeshLike,
    out: str,
    *,
    lines: Optional[Sequence[tuple[str, float]]] = None,
    svg: bool = True,
    dxf: bool = True,
    csv: bool = True,
    marked_seams: bool = True,
    threads: int = 0,
    progress: Progress = None,
) -> dict[str, Any]:
    """The made-to-measure pattern set of one garment (SVG, DXF, measurements CSV in out): its report."""

class MadeToMeasurePatterns:
    """Made-to-measure patterns of one garment topology for many bodies (prepared on a reference)."""

    def __init__(
        self,
        reference: MeshLike,
        *,
        lines: Optional[Sequence[tuple[str, float]]] = None,
        svg: bool = True,
        dxf: bool = True,
        csv: bool = True,
        marked_seams: bool = True,
        warm_start: bool = True,
        threads: int = 0,
        progress: Progress = None,
    ) -> None: ...
    def write(self, garment: MeshLike, out: str, *, threads: int = 0, progress: Progress = None) -> dict[str, Any]:
        """The pattern set of one garment of the reference's topology in out: its report."""
    @property
    def prepared(self) -> bool:
        """True when write() takes the batch form (else the one-shot form)."""
    @property
    def reason(self) -> Optional[str]:
        """Why it is not prepared, or None."""

def prepare_made_to_measure_patterns(
    templates: Union[ProfileTemplate, Sequence[ProfileTemplate]],
    reference: Body,
    *,
    levels: int = -1,
    clearance: float = -1.0,
    lines: Optional[Sequence[tuple[str, float]]] = None,
    svg: bool = True,
    dxf: bool = True,
    csv: bool = True,
    marked_seams: bool = True,
    warm_start: bool = True,
    threads: int = 0,
    progress: Progress = None,
) -> list[MadeToMeasurePatterns]:
    """Per template, the batch form prepared on it regenerated on the reference, or unprepared with its reason."""

def sketch(
    mesh: MeshLike,
    strokes: Union[Path, dict[str, Any]],
    *,
    surfaces: Optional[Sequence[str]] = None,
    keep_going: bool = False,
    threads: int = 0,
    progress: Progress = None,
) -> tuple[Mesh, dict[str, Any]]:
    """Paints, cuts and partitions a mesh with strokes: (mesh, report)."""

def extrude(
    mesh: MeshLike,
    strokes: Union[Path, dict[str, Any]],
    *,
    first: int = 0,
    pick_radius: float = 12.0,
    optimise: bool = True,
    as_surface: bool = False,
    mirror: Union[None, str, Sequence[float]] = None,
    threads: int = 0,
    progress: Progress = None,
) -> tuple[Mesh, dict[str, Any]]:
    """Extrudes a surface or cavity from a mesh by sketched strokes (seed 002): (mesh, report);
    report["recipe"] replays it with replay_extrusion."""

def replay_extrusion(
    mesh: MeshLike,
    recipe: Union[Path, dict[str, Any]],
    *,
    optimise: bool = True,
    as_surface: bool = False,
    threads: int = 0,
    progress: Progress = None,
) -> tuple[Mesh, dict[str, Any]]:
    """A recorded extrusion grown again on a mesh of the same topology: (mesh, report)."""
