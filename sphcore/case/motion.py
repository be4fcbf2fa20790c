"""Wall motion from case.toml: ``[[domain.motion]]`` (the tank) and
``[[domain.walls.motion]]`` (one finite wall), each an array of parts that add up.

    [[domain.motion]]                 # the tank: every plane, and the walls with tank = true
    type = "sine_rotation"            # roll +-4 degrees about the bottom's centre
    centre = [0.45, 0.0]
    amplitude = 4.0                   # degrees
    period = 1.63                     # s (or frequency, Hz)

    [[domain.walls]]                  # a piston wave maker
    shape = "box"
    min = [-0.1, 0.0]
    max = [0.0, 0.6]
    [[domain.walls.motion]]
    type = "sine_translation"
    axis = [1.0, 0.0]
    amplitude = 0.02                  # m
    period = 1.2
    ramp = 2.4                        # s of smooth start

Part types: ``constant_velocity`` (velocity), ``sine_translation`` (axis, amplitude,
period or frequency, phase), ``translation_file`` (file: time then dim displacement
columns, or one column along ``axis``), ``sine_rotation`` (centre, axis in 3D,
amplitude in degrees, period or frequency, phase), ``rotation_file`` (file: time and
angle in degrees; centre, axis in 3D). Every part may have ``ramp`` (s) and
``ramp_start`` (s). Files are plain text (comma, semicolon or white space between
numbers; ``#`` comments and a header line are skipped), relative to the case directory,
and must cover the run, from t = 0 to ``time.t_end``. The kinematics are in
:mod:`sphcore.geometry.motion`. Every problem is a :class:`CaseError` naming the file and
the key.
"""

from __future__ import annotations

import math
import os
import re
import stat
from pathlib import Path

import numpy as np

from sphcore.case.options import Option as O
from sphcore.case.options import validate_table
from sphcore.errors import CaseError
from sphcore.geometry.motion import (ConstantVelocity, Motion, Ramp, RotationSeries, SineRotation, SineTranslation,
                                     Spline, TranslationSeries)

MAX_SAMPLES_BYTES = 256 << 20  # a samples file larger than this is refused (a run holds it whole)

#: keys of one motion part
PART: dict[str, O] = {
    "type": O(None, "str", doc="constant_velocity, sine_translation, translation_file, sine_rotation or "
              "rotation_file", choices=("constant_velocity", "sine_translation", "translation_file", "sine_rotation",
                                        "rotation_file"), nullable=True),
    "velocity": O(None, "vector", "m/s", "constant_velocity: the velocity", nullable=True),
    "axis": O(None, "vector", doc="sine_translation: the direction of motion; translation_file with one value "
              "column: its direction; rotations in 3D: the axis (right-handed)", nullable=True),
    "amplitude": O(None, "float", doc="sine_translation: m; sine_rotation: degrees", nullable=True),
    "period": O(None, "float", "s", "sine parts: the period (or give frequency)", positive=True, nullable=True),
    "frequency": O(None, "float", "Hz", "sine parts: the frequency (or give period)", positive=True, nullable=True),
    "phase": O(0.0, "float", "deg", "sine parts: the phase at t = 0"),
    "centre": O(None, "vector", "m", "rotations: the centre of rotation, in the case's (reference) frame",
                nullable=True),
    "file": O(None, "str", doc="file parts: the samples, relative to the case directory", nullable=True),
    "scale": O(1.0, "float", doc="file parts: a factor on the file's values (-1: the opposite sense, as when "
               "a file's angle is measured the other way round; 0.001: millimetres)"),
    "ramp": O(0.0, "float", "s", "duration of the smooth start (0: none)", min=0.0),
    "ramp_start": O(0.0, "float", "s", "when the ramp starts (no motion before it)", min=0.0),
}

#: the keys each type takes besides type, ramp and ramp_start (required, optional)
TAKES = {
    "constant_velocity": (("velocity",), ()),
    "sine_translation": (("axis", "amplitude"), ("period", "frequency", "phase")),
    "translation_file": (("file",), ("axis", "scale")),
    "sine_rotation": (("centre", "amplitude"), ("axis", "period", "frequency", "phase")),
    "rotation_file": (("file", "centre"), ("axis", "scale")),
}


def _vector(file, key, value, dim, unit=False):
    v = np.asarray(value, float)
    if v.shape != (dim,):
        raise CaseError(file, key, f"expected {dim} numbers, got {value!r}")
    if unit:
        big = float(np.abs(v).max())
        if not big > 0.0:
            raise CaseError(file, key, f"expected a direction: a vector of non-zero length, got {value!r}")
        v = v / big  # no overflow in the norm of huge components
        v = v / np.linalg.norm(v)
    return v


def read_samples(path: Path, file, key, columns: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """(times (n,), values (n, m)) of a samples file: rows of numbers (m + 1 or more columns
    accepted only as exactly 1 + one of ``columns`` value columns), time increasing, at
    least two rows, every number finite."""
    try:
        st = os.stat(path)  # through a link: what would be read (a link to /dev/zero is a device)
        if not stat.S_ISREG(st.st_mode):
            what = "a directory" if stat.S_ISDIR(st.st_mode) else "not a regular file (a device, a pipe, a socket)"
            raise CaseError(file, key, f"{path}: {what}: expected a text file of samples")
        if st.st_size > MAX_SAMPLES_BYTES:
            raise CaseError(file, key, f"{path}: {st.st_size / 2**20:.0f} MiB, larger than "
                            f"{MAX_SAMPLES_BYTES >> 20} MiB: expected a text file of samples")
        text = path.read_text(encoding="utf-8", errors="strict")
    except FileNotFoundError:
        raise CaseError(file, key, f"{path}: no such file") from None
    except (OSError, ValueError, UnicodeDecodeError) as e:  # ValueError: a NUL byte in the name
        raise CaseError(file, key, f"{path}: cannot be read as text ({e})") from None
    rows = []
    for lineno, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        fields = [f for f in re.split(r"[,;\s]+", line) if f]
        try:
            numbers = [float(f) for f in fields]
        except ValueError:
            if not rows:
                continue  # a header line
            raise CaseError(file, key, f"{path}, line {lineno}: expected numbers, got {line[:60]!r}") from None
        if len(numbers) - 1 not in columns:
            want = " or ".join(str(c + 1) for c in columns)
            raise CaseError(file, key, f"{path}, line {lineno}: expected {want} columns (time, then the "
                            f"values), got {len(numbers)}")
        if rows and len(numbers) != len(rows[0]):
            raise CaseError(file, key, f"{path}, line {lineno}: {len(numbers)} columns where the first row has "
                            f"{len(rows[0])}")
        if not all(math.isfinite(x) for x in numbers):
            raise CaseError(file, key, f"{path}, line {lineno}: a number is not finite ({line[:60]!r})")
        rows.append(numbers)
    if len(rows) < 2:
        raise CaseError(file, key, f"{path}: expected at least two rows of samples, got {len(rows)}")
    data = np.asarray(rows)
    t = data[:, 0]
    step = np.diff(t)
    if np.any(step <= 0.0):
        k = int(np.argmax(step <= 0.0))
        raise CaseError(file, key, f"{path}: time must increase from row to row; row {k + 2} has t = {t[k + 1]!r} "
                        f"after t = {t[k]!r}")
    return t, data[:, 1:]


def parse_motion(file, key: str, parts: list, dim: int, case_dir: Path | None, t_end: float) -> Motion | None:
    """The :class:`Motion` of a wall group from its list of part tables (None: no part)."""
    if not parts:
        return None
    translations, rotation, centre, axis = [], None, None, None
    t_last = math.inf
    for k, entry in enumerate(parts):
        pkey = f"{key}[{k}]"
        p = validate_table(PART, entry, file, pkey)
        kind = p["type"]
        if kind is None:
            raise CaseError(file, f"{pkey}.type", "required: " + ", ".join(TAKES))
        need, may = TAKES[kind]
        for name in PART:
            if name in ("type", "ramp", "ramp_start"):
                continue
            given = name in entry
            if given and name not in need and name not in may:
                raise CaseError(file, f"{pkey}.{name}", f"not used by type = {kind!r} (it takes "
                                f"{', '.join(need + may)})")
            if name in need and not given:
                raise CaseError(file, f"{pkey}.{name}", f"required by type = {kind!r}")
        ramp = Ramp(p["ramp_start"], p["ramp"])
        omega = None
        if kind.startswith("sine"):
            if (p["period"] is None) == (p["frequency"] is None):
                raise CaseError(file, f"{pkey}.period", "give either period (s) or frequency (Hz), not both or none")
            omega = 2.0 * math.pi / p["period"] if p["period"] is not None else 2.0 * math.pi * p["frequency"]
        if kind in ("sine_rotation", "rotation_file"):
            if rotation is not None:
                raise CaseError(file, f"{pkey}.type", "a wall group has at most one rotation (rotations about "
                                "different axes do not add); give the others as translations")
            centre = _vector(file, f"{pkey}.centre", p["centre"], dim)
            if dim == 3:
                if p["axis"] is None:
                    raise CaseError(file, f"{pkey}.axis", "required by a rotation in 3D")
                axis = _vector(file, f"{pkey}.axis", p["axis"], 3, unit=True)
            elif p["axis"] is not None:
                raise CaseError(file, f"{pkey}.axis", "not used in 2D: the rotation is about the plane's normal")
        if kind == "constant_velocity":
            translations.append(ConstantVelocity(_vector(file, f"{pkey}.velocity", p["velocity"], dim), ramp))
        elif kind == "sine_translation":
            direction = _vector(file, f"{pkey}.axis", p["axis"], dim, unit=True)
            translations.append(SineTranslation(direction, p["amplitude"], omega, math.radians(p["phase"]), ramp))
        elif kind == "sine_rotation":
            rotation = SineRotation(math.radians(p["amplitude"]), omega, math.radians(p["phase"]), ramp)
        else:
            path = (Path(case_dir) / p["file"]) if case_dir is not None else Path(p["file"])
            if kind == "translation_file":
                t, values = read_samples(path, file, f"{pkey}.file", (1, dim))
                values = values * p["scale"]
                if values.shape[1] == 1:
                    if p["axis"] is None:
                        raise CaseError(file, f"{pkey}.axis", f"required: {path} has one value column, "
                                        "the displacement along axis")
                    values = values * _vector(file, f"{pkey}.axis", p["axis"], dim, unit=True)
                elif p["axis"] is not None:
                    raise CaseError(file, f"{pkey}.axis", f"not used: {path} gives all {dim} components")
                translations.append(TranslationSeries(Spline(t, values), ramp))
            else:
                t, values = read_samples(path, file, f"{pkey}.file", (1,))
                rotation = RotationSeries(Spline(t, np.radians(values * p["scale"])), ramp)
            if t[0] > 0.0 or t[-1] < t_end:
                raise CaseError(file, f"{pkey}.file", f"{path} covers t = {t[0]:g} to {t[-1]:g} s; the run needs "
                                f"t = 0 to time.t_end = {t_end:g} s")
            t_last = min(t_last, float(t[-1]))
    motion = Motion(dim, tuple(translations), rotation, centre, axis, t_last)
    start = motion.pose(0.0)
    size = max([1.0] + [abs(float(x)) for x in np.ravel(centre if centre is not None else 0.0)])
    if np.abs(start.shift).max() > 1e-9 * size or np.abs(start.rotation - np.eye(dim)).max() > 1e-12:
        raise CaseError(file, key, f"the walls must start where case.toml draws them, but at t = 0 this motion "
                        f"has moved them by {np.round(start.shift, 9).tolist()} m and turned them by "
                        f"{math.degrees(math.atan2(start.rotation[1, 0], start.rotation[0, 0])):.6g} deg; use a "
                        "phase of 0 or 180 deg, a ramp, or samples that start at 0")
    return motion
