"""SIGKILL a run at random moments, ``--restart`` it each time, and compare the end state
with an uninterrupted run, bit for bit. The suite does 3 kills; this does many.

    python benchmarks/faults/kill_restart.py --kills 12 --seed 1

Prints the kills that landed on a running process, the segments the summary records and
whether the final particles and every netCDF frame equal the uninterrupted run's.
"""

from __future__ import annotations

import argparse
import json
import random
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "tests"))  # the suite's helpers: one kill procedure, not two

from conftest import write_case  # noqa: E402
from test_run_lifecycle import CASE  # noqa: E402
from test_run_survival import CKPT, assert_same_as_reference, kill_and_restart  # noqa: E402

from sphcore import cli  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--kills", type=int, default=12)
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        case_dir = write_case(root / "mini_dam", CASE)
        ref = root / "ref"
        assert cli.main(["run", str(case_dir), "--output", str(ref), "--progress", "off", *CKPT]) == 0
        stepping_s = json.loads((ref / "summary.json").read_text())["wall_time_s"]
        out = root / "out"
        start = time.perf_counter()
        hit = kill_and_restart(case_dir, out, args.kills, random.Random(args.seed), stepping_s)
        wall = time.perf_counter() - start
        assert_same_as_reference(out, ref)  # raises on the first difference
        s = json.loads((out / "summary.json").read_text())
        print(f"kills sent {args.kills}, landed on a running process {hit}, seed {args.seed}")
        print(f"summary: {s['status']}, {s['steps']} steps over {len(s['segments'])} recorded segments "
              f"(segments killed before their first checkpoint leave no record)")
        print(f"final particles and every netCDF frame: bit for bit equal to the uninterrupted run "
              f"({stepping_s:.2f} s of stepping); {wall:.1f} s wall for the killed and restarted processes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
