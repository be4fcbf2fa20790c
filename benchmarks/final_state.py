"""Run a case to its end and save its final particles by id; or compare two saved states.

    python benchmarks/final_state.py run CASE_DIR OUT.npz [--set KEY=VALUE ...] [--t-end T]
    python benchmarks/final_state.py compare A.npz B.npz

For checking that a change keeps results bit for bit: save the state with the old commit's
checkout, then with the new one, and compare. ``compare`` prints, per array, whether the two
are equal to the last bit (np.array_equal) or the largest difference, and exits 1 if any differs.
"""

from __future__ import annotations

import argparse
import sys
import tempfile

import numpy as np


def run(args) -> int:
    from sphcore import runner

    with tempfile.TemporaryDirectory() as out:
        s = runner.run(args.case, output=out, overrides=args.overrides, t_end=args.t_end, quiet=True)
    st = s["_sim"].state
    order = np.argsort(st.id)
    np.savez(args.out, pos=st.pos[order], vel=st.vel[order], rho=st.rho[order], p=st.p[order],
             t=s["t"], steps=s["steps"])
    print(f"{args.case}: {s['status']}, {s['steps']} steps, t = {s['t']} s, saved {args.out}")
    return 0


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
    args = ap.parse_args(argv)
    return run(args) if args.command == "run" else compare(args)


if __name__ == "__main__":
    sys.exit(main())
