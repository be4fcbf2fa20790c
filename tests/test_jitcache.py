"""numba's caches follow the sources: an edit anywhere in sphcore or its plugins removes
them (numba alone checks only a cached function's own file, not what it compiled into it
from other modules), an unchanged tree keeps them, and nothing but numba's files is touched."""

from __future__ import annotations

import os
from pathlib import Path

from sphcore.jit import cache as jitcache


def _tree(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "a.py").write_text("x = 1\n")
    (pkg / "sub" / "b.py").write_text("y = 2\n")
    return pkg


def _caches(pkg):
    made = []
    for d in (pkg, pkg / "sub"):
        cache = d / "__pycache__"
        cache.mkdir(exist_ok=True)
        for name in ("m.f-3.py311.nbi", "m.f-3.py311.1.nbc"):
            (cache / name).write_bytes(b"numba")
            made.append(cache / name)
    keep = pkg / "__pycache__" / "a.cpython-311.pyc"
    keep.write_bytes(b"bytecode")
    return made, keep


def test_an_edit_removes_the_caches_and_an_unchanged_tree_keeps_them(tmp_path):
    pkg = _tree(tmp_path)
    made, keep = _caches(pkg)
    assert jitcache.refresh([pkg]) is True  # no stamp yet: whatever is there is of unknown age
    assert not any(p.exists() for p in made) and keep.exists()
    assert (pkg / "__pycache__" / jitcache.STAMP).read_text() == jitcache.stamp_of(jitcache.source_files([pkg]))
    made, keep = _caches(pkg)
    assert jitcache.refresh([pkg]) is False
    assert all(p.exists() for p in made)
    (pkg / "sub" / "b.py").write_text("y = 3  # edited\n")
    assert jitcache.refresh([pkg]) is True
    assert not any(p.exists() for p in made) and keep.exists()
    assert jitcache.refresh([pkg]) is False


def test_caches_under_numba_cache_dir_are_removed_too(tmp_path, monkeypatch):
    """numba's path rule for NUMBA_CACHE_DIR: <dir>/<source dir's name>_<sha1 of its path>."""
    pkg = _tree(tmp_path)
    cache_root = tmp_path / "numba-cache"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache_root))
    places = [d for d in jitcache.cache_dirs(jitcache.source_files([pkg])) if cache_root in d.parents]
    assert len(places) == 2 and {p.name.split("_")[0] for p in places} == {"pkg", "sub"}
    for p in places:
        p.mkdir(parents=True)
        (p / "m.f-3.py311.nbi").write_bytes(b"numba")
        (p / "notes.txt").write_text("a user's file")
    assert jitcache.refresh([pkg]) is True
    for p in places:
        assert not (p / "m.f-3.py311.nbi").exists() and (p / "notes.txt").exists()


def test_importing_sphcore_leaves_the_stamp_of_the_current_sources():
    roots = jitcache.source_roots()
    assert any(r.name == "plugins" or (r / "reflective").is_dir() for r in roots[1:])  # the plugins are covered
    stamp = roots[0] / "__pycache__" / jitcache.STAMP
    if os.access(roots[0], os.W_OK):
        assert stamp.read_text() == jitcache.stamp_of(jitcache.source_files(roots))
    assert all(Path(f).suffix == ".py" for f in jitcache.source_files(roots))
