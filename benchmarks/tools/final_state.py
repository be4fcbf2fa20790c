"""Run a case to its end and save its final particles by id; or compare two saved states.

    python benchmarks/tools/final_state.py run CASE_DIR OUT.npz [--set KEY=VALUE ...] [--t-end T]
    python benchmarks/tools/final_state.py compare A.npz B.npz
    python benchmarks/tools/final_state.py suite OUT_DIR            # the runs of SUITE, one .npz each
    python benchmarks/tools/final_state.py compare-suite A_DIR B_DIR

For checking that a change keeps results bit for bit: save the state with the old commit's
checkout, then with the new one, and compare. ``compare`` prints, per array, whether the two
are equal to the last bit (np.array_equal) or the largest difference, and exits 1 if any differs.
``suite`` runs every boundary treatment and physics option on the shipped cases (2D and 3D,
planes, faces, a mesh, a relaxed start), short enough to run in a few minutes on two cores.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
EVERYTHING = ["density_diffusion.delta=0.1", "density_diffusion.hydrostatic=true", "fluid.nu=1e-6",
              "corrections.kernel_gradient=true", "viscosity.beta=0.5"]
#: name -> (case directory, t_end (s), --set overrides)
SUITE = {
    "2d_reflective": ("dam_break", 0.06, ['plugins.use=["reflective"]']),
    "2d_wall_model": ("dam_break", 0.06, ['plugins.use=["reflective","wall_integral"]']),
    "2d_ghost": ("dam_break", 0.06, ['plugins.use=["ghost"]']),
    "2d_everything": ("dam_break", 0.06, ['plugins.use=["reflective","wall_integral"]', *EVERYTHING]),
    "2d_cubic_spline": ("dam_break", 0.06, ['plugins.use=["reflective"]', 'kernel.name="cubic_spline"']),
    "3d_reflective": ("dam_break_3d", 0.03, ['plugins.use=["reflective"]', "particles.dx=0.0114"]),
    "3d_everything": ("dam_break_3d", 0.03, ['plugins.use=["reflective","wall_integral"]', "particles.dx=0.0114",
                                              *EVERYTHING]),
    "3d_ghost_nu": ("dam_break_3d", 0.03, ['plugins.use=["ghost"]', "particles.dx=0.0114", "fluid.nu=1e-6"]),
    "2d_cylinder_mesh": ("dam_break_cylinder_2d", 0.03, ['plugins.use=["reflective","wall_integral"]']),
    "3d_faces_obstacle": ("dam_break_obstacle_3d", 0.05, ['plugins.use=["reflective","wall_integral"]',
                                                           "particles.dx=0.04", "blocks[0].max=[3.192, 1, 0.55]"]),
    "2d_relaxed_tank": ("hydrostatic_tank", 0.05, ['plugins.use=["reflective"]', "relax.time=0.05",
                                                    "particles.dx=0.04"]),
}


def _final_state(result):
    """The final particles of a run's result (the summary dict with its Simulation, or a
    result object with the run state)."""
    if isinstance(result, dict):
        return result["_sim"].state, result["t"], result["steps"], result["status"]
    return result.state.particles, result.t, result.steps, result.status


def save_run(case, out_file, overrides=(), t_end=None) -> str:
    try:
        from sphcore.run import runner
    except ImportError:  # a checkout from before the subpackages (the baseline of a comparison)
        from sphcore import runner

    with tempfile.TemporaryDirectory() as out:
        result = runner.run(case, output=out, overrides=overrides, t_end=t_end, quiet=True)
    st, t, steps, status = _final_state(result)
    order = np.argsort(st.id)
    np.savez(out_file, pos=st.pos[order], vel=st.vel[order], rho=st.rho[order], p=st.p[order], t=t, steps=steps)
    return f"{case}: {status}, {steps} steps, t = {t} s, saved {out_file}"


def run(args) -> int:
    print(save_run(args.case, args.out, args.overrides, args.t_end))
    return 0


def suite(args) -> int:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name, (case, t_end, overrides) in SUITE.items():
        if args.only and name not in args.only:
            continue
        print(name, save_run(ROOT / "cases" / case, out / f"{name}.npz", overrides, t_end), flush=True)
    return 0


def compare_suite(args) -> int:
    bad = 0
    for name in SUITE:
        a, b = Path(args.a) / f"{name}.npz", Path(args.b) / f"{name}.npz"
        if not (a.exists() and b.exists()):
            print(f"{name}: missing")
            bad += 1
            continue
        print(f"== {name}")
        bad += compare(argparse.Namespace(a=a, b=b))
    print("every run bit for bit" if bad == 0 else f"{bad} run(s) differ or are missing")
    return 1 if bad else 0


def compare(args) -> int:
    a, b = np.load(args.a), np.load(args.b)
    same = True
    for k in a.files:
        if a[k].shape == b[k].shape and np.array_equal(a[k], b[k]):
            print(f"{k:6s} bit for bit")
        else:
            same = False
            diff = np.abs(a[k] - b[k]).max() if a[k].shape == b[k].shape else "shapes differ"
            print(f"{k:6s} DIFFERENT: {diff}")
    return 0 if same else 1


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run")
    r.add_argument("case")
    r.add_argument("out")
    r.add_argument("--set", dest="overrides", action="append", default=[])
    r.add_argument("--t-end", type=float)
    c = sub.add_parser("compare")
    c.add_argument("a")
    c.add_argument("b")
    su = sub.add_parser("suite")
    su.add_argument("out")
    su.add_argument("--only", action="append", help="a run of SUITE by name (repeatable)")
    cs = sub.add_parser("compare-suite")
    cs.add_argument("a")
    cs.add_argument("b")
    args = ap.parse_args(argv)
    return {"run": run, "compare": compare, "suite": suite, "compare-suite": compare_suite}[args.command](args)


if __name__ == "__main__":
    sys.exit(main())
