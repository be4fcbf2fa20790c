"""Floating bodies from case.toml: ``[[bodies]]``, each a closed finite wall that the
fluid's loads, gravity and its springs move.

    [[domain.walls]]                  # the body's surface, drawn where it starts
    shape = "box"
    min = [0.4, 0.25]
    max = [0.6, 0.35]

    [[bodies]]
    wall = 0                          # the [[domain.walls]] entry above
    density = 500.0                   # kg/m^3 (or mass)
    free = ["y"]                      # heave only; all axes when unset
    rotation = "fixed"                # or free, or hinge (hinge_point, hinge_axis in 3D)
    orientation = [5.0]               # heeled 5 deg about its centre of mass (3D: a rotation vector)

The mass, centre of mass and inertia follow from the wall's own faces for the uniform
density (:mod:`sphcore.geometry.massprops`). Each body is a moving wall group named
``bodies[k]`` (:class:`sphcore.geometry.motion.MovingGroup`) whose motion is a
:class:`sphcore.physics.bodymotion.BodyMotion`; every plugin that honours moving walls
honours it. Every problem is a :class:`CaseError` naming the file and the key.
"""

from __future__ import annotations

import numpy as np

from sphcore.case import defaults
from sphcore.case.options import validate_table
from sphcore.errors import CaseError
from sphcore.geometry import massprops
from sphcore.geometry.faces import Faces
from sphcore.geometry.motion import MovingGroup
from sphcore.physics.bodymotion import BodyMotion
from sphcore.physics.rigid import Hinge, RigidBody, Spring

AXES = "xyz"


def _vector(file, key, value, n):
    v = np.asarray(value, float)
    if v.shape != (n,):
        raise CaseError(file, key, f"expected {n} numbers, got {value!r}")
    return v


def _turn(file, key, value, dim) -> np.ndarray:
    """The rotation matrix of ``orientation`` (degrees): an angle in 2D, a rotation vector in 3D."""
    v = np.radians(_vector(file, key, value, 1 if dim == 2 else 3))
    if dim == 2:
        c, s = np.cos(v[0]), np.sin(v[0])
        return np.array([[c, -s], [s, c]])
    angle = float(np.linalg.norm(v))
    if angle == 0.0:
        return np.eye(3)
    k = v / angle
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * cross + (1.0 - np.cos(angle)) * cross @ cross  # Rodrigues


def parse_bodies(file, cfg, dim, ranges, faces, taken, planes) -> list[MovingGroup]:
    """The body groups of the case. ``ranges``: each wall's faces; ``taken``: the walls'
    indices that already move (a prescribed motion or the tank's); ``planes``: the case's
    planes, which the bodies' vertices stay inside."""
    groups, seen = [], set()
    gravity = np.asarray(cfg["physics"]["gravity"], float)[:dim]
    for k, entry in enumerate(cfg["bodies"]):
        key = f"bodies[{k}]"
        b = validate_table(defaults.BODY, entry, file, key)
        w = b["wall"]
        if w is None:
            raise CaseError(file, f"{key}.wall", "required: the index of the [[domain.walls]] entry that is the body")
        if w >= len(ranges):
            raise CaseError(file, f"{key}.wall", f"expected an index below {len(ranges)} (the case has "
                            f"{len(ranges)} [[domain.walls]] entries)")
        if w in seen or w in taken:
            raise CaseError(file, f"{key}.wall", f"domain.walls[{w}] already moves (another body, a motion or the tank)")
        seen.add(w)
        start, stop = ranges[w]
        if not any(a == start and c == stop and sign > 0 for a, c, sign in faces.groups):
            raise CaseError(file, f"{key}.wall", f"domain.walls[{w}] is not a closed wall with the fluid outside: a "
                            "body is a box, a polygon or a closed mesh")
        if (b["density"] is None) == (b["mass"] is None):
            raise CaseError(file, f"{key}.density", "give the density or the mass, one of them")
        if b["orientation"] is not None:  # the wall turned about its centre of mass, where the fluid is built
            turn = _turn(file, f"{key}.orientation", b["orientation"], dim)
            centre = massprops.of_faces(faces.verts[start:stop], 1.0).centre
            faces.verts[start:stop] = (faces.verts[start:stop] - centre) @ turn.T + centre
        unit = massprops.of_faces(faces.verts[start:stop], 1.0)
        density = b["density"] if b["density"] is not None else b["mass"] / unit.size
        props = massprops.of_faces(faces.verts[start:stop], density)
        free = np.ones(dim)
        if b["free"] is not None:
            bad = [a for a in b["free"] if a not in AXES[:dim]]
            if bad or len(set(b["free"])) != len(b["free"]):
                raise CaseError(file, f"{key}.free", f"expected distinct axes among {list(AXES[:dim])}, got {b['free']!r}")
            free = np.array([1.0 if a in b["free"] else 0.0 for a in AXES[:dim]])
        hinge = None
        if b["rotation"] == "hinge":
            if b["hinge_point"] is None:
                raise CaseError(file, f"{key}.hinge_point", "required with rotation = \"hinge\"")
            axis = np.array([0.0, 0.0, 1.0])
            if dim == 3:
                if b["hinge_axis"] is None:
                    raise CaseError(file, f"{key}.hinge_axis", "required with rotation = \"hinge\" in 3D")
                axis = _vector(file, f"{key}.hinge_axis", b["hinge_axis"], 3)
                if not np.linalg.norm(axis) > 0:
                    raise CaseError(file, f"{key}.hinge_axis", "expected a non-zero vector")
                axis = axis / np.linalg.norm(axis)
            hinge = Hinge(axis, _vector(file, f"{key}.hinge_point", b["hinge_point"], dim))
        springs = []
        for j, raw in enumerate(b["springs"]):
            skey = f"{key}.springs[{j}]"
            s = validate_table(defaults.SPRING, raw, file, skey)
            for req in ("anchor", "stiffness"):
                if s[req] is None:
                    raise CaseError(file, f"{skey}.{req}", "required")
            attach = props.centre if s["attach"] is None else _vector(file, f"{skey}.attach", s["attach"], dim)
            springs.append(Spring(_vector(file, f"{skey}.anchor", s["anchor"], dim), attach, s["stiffness"],
                                  s["damping"], s["rest_length"]))
        v0 = np.zeros(dim) if b["velocity"] is None else _vector(file, f"{key}.velocity", b["velocity"], dim)
        body = RigidBody(dim, props.mass, props.centre, props.inertia, props.centre.copy(), free * v0,
                         free=free, rotation=b["rotation"], hinge=hinge, springs=tuple(springs))
        if b["angular_velocity"] is not None and b["rotation"] != "fixed":
            w0 = _vector(file, f"{key}.angular_velocity", b["angular_velocity"], 1 if dim == 2 else 3)
            w3 = np.array([0.0, 0.0, w0[0]]) if dim == 2 else w0
            if b["rotation"] == "hinge":
                w3 = float(w3 @ hinge.axis) * hinge.axis
                body.L = w3 * body.hinge_inertia()
                body.v = np.cross(w3, np.r_[body.x - hinge.pivot, 0.0] if dim == 2 else body.x - hinge.pivot)[:dim]
            else:
                body.L = np.array([0.0, 0.0, props.inertia[0, 0] * w3[2]]) if dim == 2 else props.inertia @ w3
        reach = float(np.sqrt(((faces.verts[start:stop].reshape(-1, dim) - props.centre) ** 2).sum(1).max()))
        idx = np.arange(start, stop, dtype=np.int64)
        vertices = np.unique(faces.verts[start:stop].reshape(-1, dim), axis=0)
        motion = BodyMotion(body, gravity, b["restitution"], vertices, (planes.normals, planes.points), b["release"],
                            faces.verts[start:stop].copy())
        groups.append(MovingGroup(key, motion, np.zeros(0, np.int64), idx, reach))
    # what a body must not enter: the fixed closed walls (an obstacle, a tank of faces) and
    # the other bodies; walls with a prescribed motion are left out (they are not where drawn)
    solids = Faces.empty(dim)
    for a, c, sign in faces.groups:
        wall = next((w for w, (r0, r1) in enumerate(ranges) if r0 <= a < r1), None)
        if wall is not None and wall not in seen and wall not in taken:
            solids = solids.concat(Faces(np.ascontiguousarray(faces.verts[a:c]), ((0, c - a, sign),)))
    for g in groups:
        g.motion.solids = solids if solids.count else None
        g.motion.others = [h.motion for h in groups if h is not g]
    return groups
