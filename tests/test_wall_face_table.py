"""The faces' wall terms from the table (``wall_integral.faces = "table"``) against the exact
boundary integrals (``"exact"``): equal at the nodes, within the interpolation error between
them (bounds from measured errors, stated beside each assertion), continuous across a face.
"""

from __future__ import annotations

import numpy as np
import pytest

from sphcore.api import build_grid
from sphcore.testing import case_with, context
from sphcore_plugins.wall_integral.facetable import build_table, table_wall_terms
from sphcore_plugins.wall_integral.facewalls import face_wall_terms, flat_parts, point_terms, stamps_for

SQUARE_2D = {
    "case": {"dim": 2},
    "domain": {"walls": [{"shape": "polygon", "fluid": "inside", "points": [[0, 0], [1, 0], [1, 1], [0, 1]]}]},
    "blocks": [{"min": [0.0, 0.0], "max": [0.5, 0.3]}],
    "particles": {"dx": 0.02},
    "time": {"t_end": 0.01},
    "plugins": {"use": ["reflective", "wall_integral"]},
}

BOX_3D = {
    "case": {"dim": 3},
    "domain": {"min": [0.0, 0.0, 0.0], "max": [0.6, 0.4, 0.4],
               "walls": [{"shape": "box", "min": [0.3, 0.1, 0.0], "max": [0.4, 0.3, 0.1], "fluid": "outside"}]},
    "blocks": [{"min": [0.0, 0.0, 0.0], "max": [0.2, 0.4, 0.2]}],
    "particles": {"dx": 0.02},
    "physics": {"gravity": [0.0, 0.0, -9.81]},
    "time": {"t_end": 0.01},
    "plugins": {"use": ["reflective", "wall_integral"]},
}


def _setup(case):
    ctx = context(case)
    prm = ctx.params
    verts = np.ascontiguousarray(ctx.case.faces.verts, dtype=np.float64)
    grid = build_grid(verts, prm.support).arrays()
    table = build_table(verts, flat_parts(verts), grid, prm.kernel_id, prm.h, prm.gravity, 0.25 * prm.h, 10 ** 7)
    return ctx, verts, grid, table


def _both(ctx, verts, grid, table, pts):
    prm = ctx.params
    n, dim = pts.shape

    def arrays():
        return np.zeros(n), np.zeros((n, dim)), np.zeros((n, dim)), np.zeros(n), np.zeros((n, dim, dim))

    exact, tab = arrays(), arrays()
    face_wall_terms(pts, verts, flat_parts(verts), *grid, stamps_for(verts.shape[0]), 1, prm.kernel_id, prm.h,
                    prm.gravity, 1.0, *exact)
    table_wall_terms(pts, table.lo, table.inv, table.shape, table.tab, 1.0, *tab)
    return exact, tab


def _fluid_points(ctx, n, seed):
    """Random points of the fluid side within 2h of a face, at least a particle radius
    (dx/2) from every face and above the floor plane (where particles can be)."""
    prm, faces = ctx.params, ctx.case.faces
    rng = np.random.default_rng(seed)
    lo = faces.verts.min(axis=(0, 1)) - 2 * prm.h
    hi = faces.verts.max(axis=(0, 1)) + 2 * prm.h
    pts = rng.uniform(lo, hi, (n, prm.dim))
    d = faces.signed_distance(pts)
    keep = (d >= 0.5 * prm.dx) & (d < 2 * prm.h)
    if prm.dim == 3:
        keep &= pts[:, 2] >= 0.5 * prm.dx
    return np.ascontiguousarray(pts[keep])


@pytest.mark.parametrize("case", [SQUARE_2D, BOX_3D], ids=["square-2d", "box-3d"])
def test_table_equals_the_exact_terms_at_its_nodes(case):
    ctx, verts, grid, table = _setup(case)
    dim = ctx.params.dim
    rng = np.random.default_rng(3)
    idx = rng.integers(0, table.shape[:dim], (400, dim))
    pts = np.ascontiguousarray(table.lo[:dim] + idx / table.inv)
    pts = pts[ctx.case.faces.signed_distance(pts) > 0]  # fluid side: the exact s there is s itself
    exact, tab = _both(ctx, verts, grid, table, pts)
    assert (exact[0] > 0).sum() > 50
    for e, t in zip(exact[:3], tab[:3]):  # to round-off: the node's position is recomputed
        assert np.allclose(t, e, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("case,bounds", [
    # measured (seed 5, grid shifted off the faces' coordinates): 2D |ds| 0.0104, |dG| h 0.0098,
    # |dTg| 0.135 m/s^2; 3D 0.0064, 0.0100, 0.146 (largest next to the box's edges)
    (SQUARE_2D, (0.015, 0.015, 0.25)),
    (BOX_3D, (0.015, 0.015, 0.25)),
], ids=["square-2d", "box-3d"])
def test_table_interpolates_within_its_stated_error(case, bounds):
    ctx, verts, grid, table = _setup(case)
    h = ctx.params.h
    pts = _fluid_points(ctx, 40_000, 5)
    assert pts.shape[0] > 2_000
    exact, tab = _both(ctx, verts, grid, table, pts)
    ds = np.abs(tab[0] - exact[0]).max()
    dg = np.linalg.norm(tab[1] - exact[1], axis=1).max() * h
    dt = np.linalg.norm(tab[2] - exact[2], axis=1).max()
    # the scale of what is interpolated: s up to 0.5, G h up to ~0.75, T g up to ~g
    assert exact[0].max() > 0.2 and (np.linalg.norm(exact[1], axis=1) * h).max() > 0.5
    assert ds < bounds[0] and dg < bounds[1] and dt < bounds[2], (ds, dg, dt)


def test_inside_a_solid_the_table_continues_s_smoothly():
    """The boundary integrals give s - 1 inside a solid; the table stores s, so that
    interpolation across a face is smooth: s grows through 0.5 at the face."""
    ctx, verts, grid, table = _setup(BOX_3D)
    prm = ctx.params
    xs = 0.4 + np.linspace(-0.02, 0.02, 41)  # across the box's face x = 0.4, at mid-height
    flat = flat_parts(verts)
    s_exact = np.array([point_terms(x, 0.2, 0.05, 3, verts, flat, *grid, stamps_for(verts.shape[0])[:1], 0, m,
                                    prm.kernel_id, prm.h, prm.gravity, np.zeros((3, 3)))[1]
                        for m, x in enumerate(xs)])
    assert s_exact[0] < -0.05 and s_exact[-1] > 0  # the jump of the formulas
    pts = np.ascontiguousarray(np.stack([xs, np.full_like(xs, 0.2), np.full_like(xs, 0.05)], 1))
    _, tab = _both(ctx, verts, grid, table, pts)
    s = tab[0]
    assert np.all(np.diff(s) < 0) and abs(s[20] - 0.5) < 0.01  # decreasing into the fluid, 0.5 on the face
    assert np.abs(np.diff(s)).max() < 0.05
    outside = xs > 0.4 + 0.5 * prm.dx
    assert np.allclose(s[outside], s_exact[outside], atol=0.01)


def test_the_plugin_uses_the_table_when_asked_and_says_so():
    table_case = case_with(SQUARE_2D, {"wall_integral.faces": "table"})
    from sphcore.physics.equations import WallTerms
    from sphcore_plugins.wall_integral import WallIntegralPlugin

    out = {}
    for key, case in (("exact", SQUARE_2D), ("table", table_case)):
        ctx = context(case)
        plugin = WallIntegralPlugin()
        plugin.sph_configure(case=ctx.case)
        n = ctx.state.n
        terms = WallTerms(np.zeros(n), np.zeros((n, 2)), np.zeros((n, 2)), np.zeros((n, 2, 2)), np.zeros(n), True)
        plugin.sph_wall_terms(ctx=ctx, terms=terms)
        out[key] = (terms, ctx.stats(plugin))
    (ex, sx), (tb, st) = out["exact"], out["table"]
    assert sx["face_terms"] == "exact" and st["face_terms"] == "table" and st["face_table_nodes"] > 1000
    near = ex.share > 0
    assert np.array_equal(near, tb.share > 0)
    h = 1.3 * 0.02
    assert np.abs(tb.share - ex.share).max() < 0.01
    assert np.linalg.norm(tb.grad - ex.grad, axis=1).max() * h < 0.012


def test_a_table_above_its_node_limit_falls_back_to_the_exact_terms():
    from sphcore.physics.equations import WallTerms
    from sphcore_plugins.wall_integral import WallIntegralPlugin

    ctx = context(case_with(SQUARE_2D, {"wall_integral": {"faces": "table", "table_max_nodes": 100}}))
    plugin = WallIntegralPlugin()
    plugin.sph_configure(case=ctx.case)
    n = ctx.state.n
    terms = WallTerms(np.zeros(n), np.zeros((n, 2)), np.zeros((n, 2)), np.zeros((n, 2, 2)), np.zeros(n), True)
    plugin.sph_wall_terms(ctx=ctx, terms=terms)
    assert ctx.stats(plugin)["face_terms"] == "exact" and ctx.stats(plugin)["face_table_nodes"] == 0
    assert (terms.share > 0).sum() > 100
