"""VTU output for ParaView: one ``.vtu`` per frame and one ``.pvd`` collection per run.

Layout below ``ctx.output_dir``::

    <name>.pvd              the collection: every frame with its simulated time (s)
    vtu/<name>_000000.vtu   one unstructured grid of vertex cells per frame
    <name>_walls.vtu        the finite walls ([[domain.walls]]): line cells (2D) or
                            triangles (3D), cell data "normal" (into the fluid); only
                            when the case has such walls

Each frame holds the particles sorted by id (the core reorders them by cell), so point i
is the same particle in every frame. 2D runs are padded to 3D points (z = 0) and 3-vector
velocities, which is what ParaView's glyph and stream filters expect. Every file is written
to a temporary name in its own directory and then renamed, so a killed or failed run never
leaves a half-written frame or collection behind.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from sphcore.api import (CaseError, Faces, Option, OutputError, ScheduledWriter, hookimpl, outline, planes_at,
                         write_atomically)

if TYPE_CHECKING:  # meshio is imported where a file is written: a run without VTU output
    import meshio  # (or a case that only names the table) does not pay its import time


TABLE = "vtu"


def run_name(ctx) -> str:
    """A file-name-safe label for the run: the case name, or "particles" when empty."""
    name = str(getattr(ctx.case, "name", "") or "")
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "particles"


def replace_atomically(path: Path, write) -> None:
    """:func:`sphcore.api.write_atomically` without the fsync: a frame is rewritten often and
    a crash loses at most the frames after the last checkpoint, which a restart writes again."""
    write_atomically(path, write, fsync=False)


VTK_TYPES = {np.dtype(np.float64): "Float64", np.dtype(np.int64): "Int64", np.dtype(np.int8): "Int8",
             np.dtype(np.uint8): "UInt8"}
VTK_VERTEX = 1  # VTK's cell type of one point
BLOCK = 32768  # bytes per compressed block, as VTK writes them
ZLIB_LEVEL = 1  # within 1 % of level 6's size for particle frames, half the time


def _encoded(a: np.ndarray, compress: bool) -> str:
    """One DataArray's text in VTK's inline ``binary`` format, header UInt64: base64 of the
    byte count and the raw bytes, or, compressed, base64 of the block table (blocks, block
    size, last block's size, each block's compressed size) then of the zlib blocks."""
    import base64
    import zlib

    raw = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<")).tobytes()  # the file says LittleEndian
    if not compress:
        return base64.b64encode(np.array([len(raw)], "<u8").tobytes() + raw).decode()
    blocks = [zlib.compress(raw[k:k + BLOCK], ZLIB_LEVEL) for k in range(0, len(raw), BLOCK)]
    last = len(raw) - BLOCK * (len(blocks) - 1) if blocks else 0
    head = np.array([len(blocks), BLOCK, last, *map(len, blocks)], "<u8")
    return base64.b64encode(head.tobytes()).decode() + base64.b64encode(b"".join(blocks)).decode()


def _data_array(name: str, a: np.ndarray, compress: bool) -> str:
    comps = f' NumberOfComponents="{a.shape[1]}"' if a.ndim == 2 else ""
    return (f'<DataArray type="{VTK_TYPES[a.dtype]}" Name="{name}"{comps} format="binary">'
            f"{_encoded(a, compress)}</DataArray>\n")


def vtu_text(points: np.ndarray, point_data: dict, compress: bool) -> str:
    """An UnstructuredGrid of one vertex cell per point, as VTK's XML with inline binary
    arrays (exact float64 values; zlib-compressed blocks when ``compress``). Written here
    rather than through meshio: meshio's writer compresses at zlib's default level 6 and
    its import (with its command line and rich) costs ~50 ms of every run's start-up."""
    n = points.shape[0]
    comp = ' compressor="vtkZLibDataCompressor"' if compress else ""
    cells = "".join(_data_array(k, v, compress) for k, v in (
        ("connectivity", np.arange(n, dtype=np.int64)), ("offsets", np.arange(1, n + 1, dtype=np.int64)),
        ("types", np.full(n, VTK_VERTEX, np.uint8))))
    data = "".join(_data_array(k, v, compress) for k, v in point_data.items())
    return ('<?xml version="1.0"?>\n'
            f'<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64"{comp}>\n'
            f'<UnstructuredGrid>\n<Piece NumberOfPoints="{n}" NumberOfCells="{n}">\n'
            f'<Points>\n{_data_array("Points", points, compress)}</Points>\n'
            f"<Cells>\n{cells}</Cells>\n<PointData>\n{data}</PointData>\n"
            "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")


def frame_arrays(state) -> tuple[np.ndarray, dict]:
    """The particles sorted by id, padded to 3D: points and point data.

    Point data: velocity (m/s, 3 components), pressure (Pa), density (kg/m^3), mass (kg),
    radius (m), kind, id. The frame time lives in the .pvd.
    """
    order = np.argsort(state.id, kind="stable")
    n, dim = state.pos.shape
    points = np.zeros((n, 3))
    points[:, :dim] = state.pos[order]
    velocity = np.zeros((n, 3))
    velocity[:, :dim] = state.vel[order]
    point_data = {
        "velocity": velocity,
        "pressure": np.ascontiguousarray(state.p[order], dtype=np.float64),
        "density": np.ascontiguousarray(state.rho[order], dtype=np.float64),
        "mass": np.ascontiguousarray(state.m[order], dtype=np.float64),
        "radius": np.ascontiguousarray(state.radius[order], dtype=np.float64),
        "kind": np.ascontiguousarray(state.kind[order], dtype=np.int8),
        "id": np.ascontiguousarray(state.id[order], dtype=np.int64),
    }
    return points, point_data


def walls_mesh(faces) -> meshio.Mesh:
    """Wall faces as a meshio Mesh (points padded to 3D), cell data "normal" (3 components)."""
    import meshio

    nf, dim = faces.count, faces.dim
    pts = np.zeros((nf * dim, 3))
    pts[:, :dim] = faces.verts.reshape(-1, dim)
    normals = np.zeros((nf, 3))
    normals[:, :dim] = faces.normals()
    cells = np.arange(nf * dim).reshape(nf, dim)
    return meshio.Mesh(pts, [("line" if dim == 2 else "triangle", cells)], cell_data={"normal": [normals]})


def wall_frame(rel: str, name: str) -> str:
    """The walls' file beside the particle frame ``rel`` (``vtu/<name>_<k>.vtu``)."""
    head, _, index = rel.rpartition("_")
    return f"{head}_walls_{index}"


def walls_at(case, t: float):
    """The faces (nf, dim, dim) of every wall at time t: fixed faces as case.toml draws them,
    moving groups' faces at their pose, and the outline of the planes where they are (the
    tank's carried with it, a piston's moved on its own), or None without any."""
    faces = getattr(case, "faces", None)
    nf = faces.count if faces is not None else 0
    parts = []
    verts = faces.verts.copy() if nf else None
    moving = getattr(case, "moving", ())
    for g in moving:
        if len(g.faces):
            verts[g.faces] = g.motion.pose(t).to_world(faces.verts[g.faces])
    if nf:
        parts.append(verts)
    box = None
    if case.planes.count:
        tank = [g for g in moving if len(g.planes)]
        if len(tank) == 1 and len(tank[0].planes) == case.planes.count:  # the tank's outline, carried
            box = outline(case.planes)
            box = tank[0].motion.pose(t).to_world(box) if box is not None else None
        else:  # fixed planes, or a piston among them: the outline of the planes where they are
            box = outline(planes_at(case.planes, moving, t))
    if box is not None:
        parts.append(box)
    return np.ascontiguousarray(np.concatenate(parts)) if parts else None


def pvd_text(frames: list[tuple[float, str]]) -> str:
    """A ParaView collection listing ``(time in s, path relative to the pvd)`` frames."""
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    coll = ET.SubElement(root, "Collection")
    for t, rel in frames:
        # repr() gives the shortest string that reads back as the same float64
        ET.SubElement(coll, "DataSet", timestep=repr(float(t)), group="", part="0", file=rel)
    ET.indent(root)
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def whole_frame(path: Path) -> bool:
    """Whether ``path`` is a regular file that ends as :func:`vtu_text` ends a frame."""
    tail = b"</VTKFile>\n"
    try:
        if path.is_symlink() or not path.is_file() or path.stat().st_size < len(tail):
            return False
        with open(path, "rb") as f:
            f.seek(-len(tail), 2)
            return f.read() == tail
    except OSError:
        return False


def read_pvd(path: Path) -> list[tuple[float, str]]:
    """The ``(time, relative file)`` frames of a collection written by :func:`pvd_text`."""
    root = ET.parse(path).getroot()
    return [(float(e.get("timestep")), e.get("file")) for e in root.iter("DataSet")]


class VtuWriter(ScheduledWriter):
    """Pluggy plugin ``vtu``: particle frames for ParaView on the ``[vtu]`` schedule."""

    table = TABLE
    what = "VTU frame"

    def __init__(self):
        super().__init__()
        self.frames: list[tuple[float, str]] = []  # (t in s, file relative to output_dir)
        self.compress = True

    @hookimpl
    def sph_options(self):
        return {TABLE: {**super().sph_options()[TABLE], "compress": Option(
            True, "bool", doc="zlib-compress each frame's arrays (level 1): about half the file size, a few times "
            "the write time; may change on --restart (each frame says how it is written)",
            restart=True)}}

    @hookimpl
    def sph_configure(self, case):
        super().sph_configure(case)
        self.compress = bool(case.config.get(TABLE, {}).get("compress", True))

    @hookimpl
    def sph_summary(self, ctx):
        return {"frames": len(self.frames)} if self.frames else None

    @hookimpl
    def sph_finish(self, ctx):
        pass  # every file is complete and closed once its frame is written

    # ---------------------------------------------------------------- writing

    def pvd_path(self, ctx) -> Path:
        return Path(ctx.output_dir) / f"{run_name(ctx)}.pvd"

    def write_frame(self, ctx) -> Path:
        """Write the current state as the next frame and rewrite the collection; returns the .vtu."""
        if ctx.output_dir is None:
            raise OutputError("vtu: this run has no output directory")
        out = Path(ctx.output_dir)
        name = run_name(ctx)
        rel = f"vtu/{name}_{len(self.frames):06d}.vtu"
        path = out / rel
        try:
            path.parent.mkdir(exist_ok=True)
        except OSError as err:
            raise OutputError(f"{path.parent}: cannot create directory: {err.strerror or err}") from err
        walls = getattr(ctx.case, "faces", None)
        if getattr(ctx.case, "moving", ()):
            self._write_moving_walls(ctx, out, name, rel)
        elif walls is not None and walls.count and not (out / f"{name}_walls.vtu").exists():
            import meshio

            wmesh = walls_mesh(walls)
            replace_atomically(out / f"{name}_walls.vtu",
                               lambda tmp: meshio.write(tmp, wmesh, file_format="vtu", binary=True))
        # binary: base64 of the raw float64 bytes, so the file holds exact values
        frame = vtu_text(*frame_arrays(ctx.host()), compress=self.compress)
        replace_atomically(path, lambda tmp: tmp.write_text(frame))
        self.frames.append((float(ctx.t), rel))
        collection = pvd_text(self.frames)
        replace_atomically(self.pvd_path(ctx), lambda tmp: tmp.write_text(collection))
        return path

    def _write_moving_walls(self, ctx, out: Path, name: str, rel: str) -> None:
        """The walls where they are at ctx.t, beside the frame ``rel`` (``vtu/<name>_walls_<k>.vtu``,
        listed in ``<name>_walls.pvd``): the finite faces of every group moved by its pose, and
        the outline of the tank's planes (where they enclose a region)."""
        import meshio

        verts = walls_at(ctx.case, ctx.t)
        if verts is None:
            return
        wrel = wall_frame(rel, name)
        wmesh = walls_mesh(Faces(verts))
        replace_atomically(out / wrel, lambda tmp: meshio.write(tmp, wmesh, file_format="vtu", binary=True))
        frames = [(t, wall_frame(r, name)) for t, r in self.frames] + [(float(ctx.t), wrel)]
        collection = pvd_text(frames)
        replace_atomically(out / f"{name}_walls.pvd", lambda tmp: tmp.write_text(collection))

    def frames_on_disk(self, ctx):
        """The collection's frames (time, None) for a restart's check; a frame up to the
        restart whose file is missing, not a regular file or cut (not ending as a frame
        ends) is a CaseError naming that file."""
        pvd = self.pvd_path(ctx)
        if pvd.is_symlink():
            return None  # the output directory refuses it
        if not pvd.exists():
            return pvd, None
        redo = "restore it, or run again with --overwrite (or --output DIR)"
        try:
            if not pvd.is_file():
                raise OSError("not a regular file")
            frames = read_pvd(pvd)
            if not all(isinstance(rel, str) and rel for _, rel in frames):
                raise ValueError("a DataSet without a file")
        except (OSError, ET.ParseError, ValueError, TypeError) as err:
            raise CaseError(pvd, "--restart", f"not a readable collection ({err}); {redo}") from None
        for t, rel in frames:
            if t <= ctx.t and not whole_frame(Path(ctx.output_dir) / rel):
                raise CaseError(Path(ctx.output_dir) / rel, "--restart", f"the frame at t = {t!r} s that {pvd.name} "
                                f"lists is missing, cut or not a regular file; {redo}")
        return pvd, [(t, None) for t, _ in frames]

    def reopen_for_restart(self, ctx) -> None:
        """Continue the collection of an earlier run; frames up to ``ctx.t`` are kept.

        Called with ``ctx`` at the restart point or at the first step after it (the first
        output of a restarted run). Frames later than ``ctx.t`` (written after the
        checkpoint) are dropped from the collection and their files removed; a frame at
        ``ctx.t`` itself holds the same state (checkpoints restart bit for bit) and stays.
        Numbering goes on after the frames kept; the schedule counts them as written.
        """
        if ctx.output_dir is None or not self.pvd_path(ctx).exists():
            return  # nothing written before: numbering starts at 0
        pvd = self.pvd_path(ctx)
        try:
            frames = read_pvd(pvd)
        except (OSError, ET.ParseError) as err:
            raise OutputError(f"{pvd}: cannot read the collection to restart: {err}") from err
        # exact comparison: both times are the same float64 (repr round-trips)
        keep = [f for f in frames if f[0] <= ctx.t]
        frame_dir = (Path(ctx.output_dir) / "vtu").resolve()
        name = run_name(ctx)
        moving = bool(getattr(ctx.case, "moving", ()))
        for _, rel in (f for f in frames if f[0] > ctx.t):
            for one in ([rel, wall_frame(rel, name)] if moving else [rel]):
                stale = (Path(ctx.output_dir) / one).resolve()
                if stale.parent != frame_dir:
                    continue  # not a frame of ours (an edited collection): never delete it
                try:
                    stale.unlink(missing_ok=True)
                except OSError as err:
                    raise OutputError(f"{stale}: cannot remove: {err.strerror}") from err
        self.frames = keep
        replace_atomically(pvd, lambda tmp: tmp.write_text(pvd_text(keep)))
        if moving:
            walls_pvd = Path(ctx.output_dir) / f"{name}_walls.pvd"
            text = pvd_text([(t, wall_frame(r, name)) for t, r in keep])
            replace_atomically(walls_pvd, lambda tmp: tmp.write_text(text))
        if keep:
            t_last = keep[-1][0]
            self.schedule.resume(t_last, ctx.step if t_last == ctx.t else None)
