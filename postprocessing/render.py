"""Pictures of a run: its frames rendered off-screen with pyvista, and an animated GIF.

Reads   RUN, the output directory of a run with the vtu plugin (or its .pvd): the frames,
        the walls it wrote (<name>_walls.vtu for fixed finite walls, <name>_walls.pvd for
        walls that move, one file per frame) and summary.json (the domain's box and planes,
        drawn as the tank).
Writes  OUT/<field>_<k>.png for each frame k chosen (OUT: RUN/render unless --out), and with
        --gif OUT/<field>.gif, the frames animated (Pillow); prints each file written.

The particles are drawn as spheres coloured by the field (pressure in Pa, the velocity's
magnitude in m/s or density in kg/m^3) on one colour scale for every frame (the 1st and
99th percentiles of the frames drawn, or --range), with a scalar bar and the time as
title; the walls in dark grey. A 2D run is seen from +z in parallel projection, a 3D run
from an isometric viewpoint (--view). No display is needed. A path that is not a run with
VTU frames, or a bad option: one line on stderr, exit status 2.

    python postprocessing/render.py cases/dam_break/output --field pressure --frames last
    python postprocessing/render.py cases/dam_break/output --field velocity --gif --size 480x360
"""

from __future__ import annotations

import argparse
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from runs import RunError, open_run, refuse
from sphcore_plugins.vtu import read_pvd

PROG = Path(__file__).name
FIELDS = {"pressure": ("pressure [Pa]", "turbo"), "velocity": ("speed [m/s]", "viridis"),
          "density": ("density [kg/m^3]", "coolwarm")}
GHOST = 2  # the ghost plugin's mirror particles (sphcore.api.GHOST): not drawn
WALL_COLOUR = "#404040"


def pvd_frames(pvd: Path) -> list[tuple[float, Path]]:
    """(t in s, .vtu path) of every frame a collection lists."""
    try:
        frames = [(t, pvd.parent / f) for t, f in read_pvd(pvd)]
    except (OSError, ET.ParseError, TypeError, ValueError) as err:
        raise RunError(f"{pvd}: not a readable collection of frames ({err})") from None
    if not frames:
        raise RunError(f"{pvd}: no frame written yet")
    return frames


def read_mesh(path: Path, what: str):
    import pyvista as pv

    try:
        mesh = pv.read(path) if path.is_file() else None
    except (OSError, ValueError, RuntimeError, KeyError) as err:
        raise RunError(f"{path}: cannot read the {what}: {err}") from None
    if mesh is None or mesh.n_points == 0:
        raise RunError(f"{path}: not a readable {what} (missing, empty or corrupt)")
    if what == "walls" and not isinstance(mesh, pv.PolyData):  # line cells (2D) or triangles (3D)
        lines = mesh.n_cells and mesh.get_cell(0).dimension == 1
        mesh = pv.PolyData(mesh.points, lines=mesh.cells) if lines else pv.PolyData(mesh.points, faces=mesh.cells)
    return mesh


def choose(spec: str, n: int) -> list[int]:
    """Frame indices from ``all``, ``last`` or ``N,M,...`` (negative: from the end)."""
    if spec in ("all", "last"):
        return list(range(n)) if spec == "all" else [n - 1]
    try:
        picked = [int(s) for s in spec.split(",")]
    except ValueError:
        raise RunError(f"--frames {spec!r}: expected all, last or frame numbers N,M,...") from None
    bad = [k for k in picked if not -n <= k < n]
    if bad:
        raise RunError(f"--frames {spec!r}: the run has {n} frames (0 to {n - 1}), not frame {bad[0]}")
    return sorted({k % n for k in picked})


def pair(text: str, sep: str, what: str, kind=float):
    try:
        a, b = (kind(s) for s in text.split(sep))
    except ValueError:
        raise RunError(f"{what} {text!r}: expected two numbers A{sep}B") from None
    if kind is float and not (np.isfinite(a) and np.isfinite(b) and a < b):
        raise RunError(f"{what} {text!r}: expected finite numbers A < B")
    if kind is int and not (0 < a <= 8192 and 0 < b <= 8192):
        raise RunError(f"{what} {text!r}: expected a width and a height in pixels, up to 8192")
    return a, b


def plane_walls(config: dict):
    """The outline of the domain's box and planes (segments in 2D, triangles in 3D), or None."""
    from sphcore.api import Planes, outline

    try:
        dom, dim = config.get("domain") or {}, int(config["case"]["dim"])
        normals, points = [], []
        if dom.get("min") is not None and dom.get("max") is not None:
            box = Planes.box(dom["min"], dom["max"])
            normals, points = list(box.normals), list(box.points)
        for p in dom.get("planes") or []:
            normals.append(p["normal"]), points.append(p["point"])
        faces = outline(Planes.from_lists(normals, points)) if len(normals) > dim else None
    except (KeyError, TypeError, ValueError, AttributeError, np.linalg.LinAlgError) as err:
        raise RunError(f"summary.json: its domain is not a validated case's ({type(err).__name__}: {err})") from None
    return None if faces is None else (faces, dim)


def faces_mesh(faces, dim: int):
    import pyvista as pv

    nf = faces.shape[0]
    pts = np.zeros((nf * dim, 3))
    pts[:, :dim] = faces.reshape(-1, dim)
    cells = np.c_[np.full(nf, dim), np.arange(nf * dim).reshape(nf, dim)].ravel()
    return pv.PolyData(pts, lines=cells) if dim == 2 else pv.PolyData(pts, faces=cells)


def render(frame, walls, args, setting) -> np.ndarray:
    """One frame as an RGB image (h, w, 3); ``setting``: bounds (m), colour scale, run name."""
    import pyvista as pv

    t, mesh = frame
    bounds, clim, name = setting
    label, cmap = FIELDS[args.field]
    w, h = args.size
    pl = pv.Plotter(off_screen=True, window_size=(w, h))
    pl.set_background("white")
    for wall in walls:  # lines in 2D or where the walls are lines; surfaces and their edges in 3D
        if wall.n_lines:
            pl.add_mesh(wall, color=WALL_COLOUR, line_width=3)
        elif wall.n_cells:  # faces share their corners once merged (clean): no edge inside a flat wall
            wall = wall.clean()
            pl.add_mesh(wall, color="lightgrey", opacity=0.15)
            pl.add_mesh(wall.extract_feature_edges(30.0), color=WALL_COLOUR, line_width=2)
    lo, hi = np.array(bounds[::2]), np.array(bounds[1::2])
    centre, size = (lo + hi) / 2, np.maximum(hi - lo, 1e-9)
    if args.view == "iso":
        pl.view_isometric()
        pl.reset_camera(bounds=bounds)
        pl.camera.zoom(1.1)
    else:  # seen from +z (xy), -y (xz) or +x (yz), the domain in the left 80 % of the image
        i, j, k = {"xy": (0, 1, 2), "xz": (0, 2, 1), "yz": (1, 2, 0)}[args.view]
        pl.enable_parallel_projection()
        scale = 0.5 * 1.08 * max(size[j] / 0.86, size[i] / (0.78 * w / h))
        focal = centre.copy()
        focal[i] += 0.1 * 2 * scale * w / h
        focal[j] += 0.03 * 2 * scale
        pos = focal.copy()
        pos[k] += (-1 if args.view == "xz" else 1) * 10 * size.max()
        pl.camera_position = [tuple(pos), tuple(focal), tuple(np.eye(3)[j])]
        pl.camera.parallel_scale = scale
        pl.reset_camera_clipping_range()
    cam = pl.camera
    height_m = (2 * cam.parallel_scale if args.view != "iso"
                else 2 * cam.distance * np.tan(np.radians(cam.view_angle) / 2))
    radius = float(np.median(mesh.point_data["radius"])) if "radius" in mesh.point_data else size.max() / 100
    bar = {"title": label, "vertical": True, "position_x": 0.86, "position_y": 0.08, "height": 0.72, "width": 0.06,
           "color": "black", "title_font_size": max(10, h // 40), "label_font_size": max(9, h // 48), "fmt": "%.4g"}
    spheres = args.view == "iso"  # in a plane view flat squares, 1.3 spacings wide: the fluid is filled
    pl.add_mesh(mesh, scalars="_shown", cmap=cmap, clim=clim, render_points_as_spheres=spheres,
                point_size=max(2, np.ceil((2.5 if spheres else 2.6) * radius * h / height_m)), scalar_bar_args=bar)
    pl.add_text(f"{name}    t = {t:.3f} s", position="upper_edge", font_size=max(8, h // 45), color="black")
    image = pl.screenshot(return_img=True)
    pl.close()
    return np.asarray(image)[..., :3]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="a run's output directory or its .pvd (the vtu plugin's frames)")
    ap.add_argument("--field", choices=sorted(FIELDS), default="pressure", help="colour by (default pressure)")
    ap.add_argument("--frames", default="all", help="all (default), last, or frame numbers N,M,... (from 0; "
                    "negative: from the end)")
    ap.add_argument("--gif", action="store_true", help="also write OUT/<field>.gif of the frames chosen")
    ap.add_argument("--fps", type=float, default=10.0, help="frames per second of the GIF (default 10)")
    ap.add_argument("--out", help="directory of the pictures (default RUN/render)")
    ap.add_argument("--size", default="800x600", help="image width x height in pixels (default 800x600)")
    ap.add_argument("--range", help="colour scale LO,HI in the field's unit (default: from the frames)")
    ap.add_argument("--view", choices=["xy", "xz", "yz", "iso"], help="viewpoint (default xy in 2D, iso in 3D)")
    args = ap.parse_args(argv)
    from vtkmodules.vtkCommonCore import vtkLogger, vtkObject

    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)  # not the harmless "bad X server connection"
    vtkObject.GlobalWarningDisplayOff()  # a corrupt frame is reported as one line, not VTK's error dump
    try:
        args.size = pair(args.size.lower(), "x", "--size", int)
        clim = pair(args.range, ",", "--range") if args.range else None
        if not (np.isfinite(args.fps) and 0 < args.fps <= 100):
            raise RunError(f"--fps {args.fps}: expected a rate in (0, 100] frames per second")
        run = open_run(args.run)
        pvd = run.frames_file()
        if pvd.suffix != ".pvd" or pvd.stem.endswith("_walls"):
            raise RunError(f"{pvd}: {PROG} reads the vtu plugin's frames (a .pvd); add vtu to plugins.use")
        frames = pvd_frames(pvd)
        picked = choose(args.frames, len(frames))
        meshes = []
        for k in picked:
            t, path = frames[k]
            mesh = read_mesh(path, "frame")
            if args.field not in mesh.point_data:
                raise RunError(f"{path}: no point data {args.field!r} in this frame")
            if "kind" in mesh.point_data:
                mesh = mesh.extract_points(np.asarray(mesh.point_data["kind"]) != GHOST, adjacent_cells=False)
            values = np.asarray(mesh.point_data[args.field], float)
            mesh.point_data["_shown"] = np.linalg.norm(values, axis=1) if values.ndim == 2 else values
            meshes.append((t, mesh))
        fixed = [read_mesh(p, "walls") for p in [pvd.with_name(pvd.stem + "_walls.vtu")] if p.is_file()]
        moving = pvd.with_name(pvd.stem + "_walls.pvd")
        moved = dict(pvd_frames(moving)) if moving.is_file() else {}
        moved = {t: read_mesh(moved[t], "walls") for t, _ in meshes if t in moved}
        planes = plane_walls(run.config) if run.config and not moved else None
        fixed += [faces_mesh(*planes)] if planes is not None else []
    except RunError as err:
        return refuse(PROG, err)
    dim = int((run.config.get("case") or {}).get("dim", 3 if np.ptp(meshes[0][1].points[:, 2]) > 0 else 2))
    args.view = args.view or ("xy" if dim == 2 else "iso")
    dom = run.config.get("domain") or {}
    if dom.get("min") is not None:
        lo, hi = np.zeros(3), np.zeros(3)
        lo[:dim], hi[:dim] = dom["min"], dom["max"]
    else:
        boxes = np.array([m.bounds for m in [meshes[0][1], *fixed]])
        lo, hi = boxes[:, ::2].min(axis=0), boxes[:, 1::2].max(axis=0)
    shown = np.concatenate([m.point_data["_shown"] for _, m in meshes])
    if clim is None:
        clim = tuple(np.nan_to_num(np.nanpercentile(shown, [1, 99]) if np.isfinite(shown).any() else [0.0, 1.0]))
        clim = clim if clim[1] > clim[0] else (clim[0] - 0.5, clim[0] + 0.5)
    setting = (np.ravel(np.c_[lo, hi]), clim, pvd.stem)
    out = Path(args.out) if args.out else run.dir / "render"
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        return refuse(PROG, RunError(f"{out}: cannot create the directory of the pictures: {err.strerror or err}"))
    from PIL import Image

    images = []
    for k, frame in zip(picked, meshes):
        walls = fixed + ([moved[frame[0]]] if frame[0] in moved else [])
        images.append(render(frame, walls, args, setting))
        png = out / f"{args.field}_{k:06d}.png"
        Image.fromarray(images[-1]).save(png, optimize=True)
        print(f"{png}  t = {frame[0]:.4g} s")
    if args.gif:
        gif = out / f"{args.field}.gif"
        first, *rest = [Image.fromarray(a).quantize(colors=128) for a in images]
        first.save(gif, save_all=True, append_images=rest, duration=round(1000 / args.fps), loop=0, optimize=True)
        print(f"{gif}  {len(images)} frames")
    return 0


if __name__ == "__main__":
    sys.exit(main())
