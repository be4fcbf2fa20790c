"""A real full disk: run the mini dam break into a small tmpfs filled so that only
FREE bytes are left, for many values of FREE, so the disk fills at a frame, a checkpoint,
the summary or front.csv. Each run must exit 1 with one line, leave no temporary file and
a readable checkpoint and netCDF file; after freeing the space ``--restart`` must finish
with the uninterrupted run's end state, bit for bit. Needs root (mount); Linux only.

    sudo python benchmarks/faults/full_disk.py --free 0,8,32,64,128,256,512,768,1024,1536

FREE in KiB. Prints one line per fill level and ``N fill levels, K failed``; exit 1 if any
failed. Where no tmpfs can be mounted (not root, not Linux, no permission) it says so in
one line and exits with status 77 (UNAVAILABLE). The suite injects ENOSPC at each write
point instead (tests/test_full_disk.py).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "tests"))

from conftest import write_case  # noqa: E402
from test_run_lifecycle import CASE, checkpoint_by_id, netcdf_frames, sph_command, stray_files  # noqa: E402
from test_run_survival import CKPT, assert_same_as_reference  # noqa: E402

GAUGED = CASE.replace('"netcdf"]', '"netcdf", "front_gauge"]')
#: exit status when no tmpfs can be mounted here: the drill cannot run
UNAVAILABLE = 77


def sph(*argv):
    return subprocess.run(sph_command() + [str(a) for a in argv], capture_output=True, text=True, timeout=300)


def mount_tmpfs(mnt: Path, size_mib: int) -> str:
    """Mount a tmpfs of ``size_mib`` MiB on ``mnt``; "" when mounted, else why not."""
    if not sys.platform.startswith("linux"):
        return f"needs Linux (this is {sys.platform})"
    if os.geteuid() != 0:
        return "needs root to mount a tmpfs (run it with sudo)"
    if shutil.which("mount") is None:
        return "no mount command"
    res = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size_mib}m", "tmpfs", str(mnt)],
                         capture_output=True, text=True)
    return "" if res.returncode == 0 else f"mount failed: {res.stderr.strip() or res.returncode}"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--free", default="0,8,32,64,128,256,512,768,1024,1536", help="KiB left free, comma separated")
    p.add_argument("--size-mib", type=int, default=8, help="tmpfs size")
    args = p.parse_args(argv)
    free_kib = [int(v) for v in args.free.split(",")]
    failures = 0
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        mnt = root / "disk"
        mnt.mkdir()
        why = mount_tmpfs(mnt, args.size_mib)
        if why:
            print(f"full_disk: cannot run here: {why}", file=sys.stderr)
            return UNAVAILABLE
        try:
            case_dir = write_case(root / "mini_dam", GAUGED)
            ref = root / "ref"
            res = sph("run", case_dir, "--output", ref, "--progress", "off", *CKPT)
            assert res.returncode == 0, res.stderr
            for free in free_kib:
                for p_ in mnt.iterdir():
                    subprocess.run(["rm", "-rf", str(p_)], check=True)
                filler = mnt / "filler"
                st = os.statvfs(mnt)
                avail = st.f_bavail * st.f_frsize
                with open(filler, "wb") as f:
                    f.write(b"\0" * max(0, avail - free * 1024))
                out = mnt / "out"
                res = sph("run", case_dir, "--output", out, "--progress", "off", *CKPT)
                lines = res.stderr.strip().splitlines()
                first = res.returncode
                ok = "Traceback" not in res.stderr and stray_files(out) == [] if out.exists() else True
                where = lines[-1][:150] if lines else ""
                again = "--restart"
                if res.returncode == 1:
                    ok = ok and len(lines) == 1 and "No space left" in lines[0]
                    if (out / "checkpoint.npz").exists():
                        checkpoint_by_id(out)  # loads
                        if (out / "particles.nc").exists():
                            netcdf_frames(out)  # readable
                    else:  # the disk filled before the first checkpoint: nothing to continue
                        ok = ok and "no checkpoint could be written: run again with --overwrite" in lines[0]
                        again = "--overwrite"
                elif res.returncode == 2:  # not even the directory and its first checkpoint fit
                    ok = ok and len(lines) == 1
                filler.unlink()
                if res.returncode in (0, 1):
                    res2 = sph("run", case_dir, "--output", out, "--progress", "off", again, *CKPT)
                    ok = ok and res2.returncode == 0
                    if res2.returncode == 0:
                        assert_same_as_reference(out, ref)
                    else:
                        where += f" | restart: {res2.stderr.strip()[:200]}"
                failures += not ok
                print(f"free {free:5d} KiB: exit {first}, {'ok' if ok else 'FAILED'}: {where}")
        finally:
            subprocess.run(["umount", str(mnt)], check=False)
    print(f"{len(free_kib)} fill levels, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
