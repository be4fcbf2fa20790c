"""The documentation: it builds with warnings as errors, the README stays a front page, and
the product speaks of the product (no work log in docs, docstrings or comments).

The build test runs Sphinx as a user would (``python -m sphinx -W -b html docs DIR``): a
broken link, a page outside every table of contents, a reference to a function that is
gone or a case key the reference generator cannot describe fails it."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: what a work log leaves behind: a session, an issue number, a date
WORK_LOG = re.compile(r"\bsessions?\b|\bissues? ?#?\d+|\b20\d\d-[01]\d-[0-3]\d\b", re.IGNORECASE)
TEXT = {".py", ".md", ".toml", ".txt", ".rst", ".cfg", ".sh", ".json", ".yml", ".yaml"}
SKIP = {".git", "__pycache__", "_build", "build", "dist", "runs", ".hypothesis", ".pytest_cache", ".venv"}


#: the project's own folders and files: a virtual environment or a user's runs beside them
#: are not the project's text
OWN = ("sphcore", "plugins", "cases", "tests", "postprocessing", "docs", "validation", "benchmarks", "examples", ".ci")
OWN_FILES = ("README.md", "pyproject.toml", "setup.py")


def _sources():
    paths = [ROOT / f for f in OWN_FILES] + [p for d in OWN for p in (ROOT / d).rglob("*")]
    for path in sorted(paths):
        rel = path.relative_to(ROOT)
        if (set(rel.parts) & SKIP or rel.parts[0].endswith(".egg-info") or not path.is_file()
                or any(p.startswith("output") or p.startswith("sweep") for p in rel.parts[2:3])):
            continue
        if path.suffix in TEXT or rel.as_posix() == ".ci/run":
            yield rel, path


def test_no_work_log_in_docs_docstrings_or_comments():
    """No "session", "issue 12" or 2026-11-24 anywhere in the tree's text: the history is in
    git; what it found that matters is in the explanation and validation pages."""
    found = []
    for rel, path in _sources():
        if path == Path(__file__).resolve():  # this test names what it looks for
            continue
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            if WORK_LOG.search(line):
                found.append(f"{rel}:{n}: {line.strip()[:100]}")
    assert not found, "work-log words:\n" + "\n".join(found)


def test_the_work_log_pattern_finds_what_it_should_and_nothing_else():
    assert WORK_LOG.search("as measured in the third session")
    assert WORK_LOG.search("see issue 14") and WORK_LOG.search("Issue #3") and WORK_LOG.search("on 2026-11-24")
    assert not WORK_LOG.search("the issue is the kernel width") and not WORK_LOG.search("dx = 2026.5")


#: a path into the documentation named in the tree's text
DOCS_PATH = re.compile(r"\bdocs/[\w/.-]*\w\.(?:md|png|gif|py)\b")


def test_every_documentation_page_the_tree_names_exists():
    """A docstring, comment, README or case file that points at a page points at one that is
    there: a page renamed or removed leaves no reference behind."""
    missing = []
    for rel, path in _sources():
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            missing += [f"{rel}:{n}: {m}" for m in DOCS_PATH.findall(line) if not (ROOT / m).exists()
                        and not m.startswith("docs/reference/")]  # reference pages are written at build time
    assert not missing, "pointers to pages that are not there:\n" + "\n".join(missing)


def test_every_script_the_documentation_runs_exists():
    """``python some/script.py`` in a page or the README names a script of the tree."""
    missing = []
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        if "_build" in page.parts:
            continue
        for n, line in enumerate(page.read_text().splitlines(), 1):
            missing += [f"{page.relative_to(ROOT)}:{n}: {script}"
                        for script in re.findall(r"python3? ([\w/.-]+\.py)\b", line) if not (ROOT / script).is_file()]
    assert not missing, "scripts that are not there:\n" + "\n".join(missing)


def test_the_readme_is_a_front_page_with_two_quick_start_commands():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 120
    quick = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```bash\n(.*?)```", quick, re.S)
    assert len(commands) == 1 and len(commands[0].strip().splitlines()) == 2
    install_run, install_test = commands[0].strip().splitlines()
    assert install_run.startswith("pip install") and "sph run" in install_run
    assert install_test.startswith("pip install") and "pytest" in install_test
    ci = (ROOT / ".ci" / "run").read_text()
    assert install_test in ci, ".ci/run runs the README's test command verbatim"
    for image in re.findall(r"!\[[^]]*\]\(([^)]+)\)", text):
        assert (ROOT / image).is_file(), f"the README shows {image}, which is not in the tree"


@pytest.mark.slow
def test_the_documentation_builds_with_warnings_as_errors(tmp_path):
    done = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html", str(ROOT / "docs"),
                           str(tmp_path / "html")], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-4000:]
    index = (tmp_path / "html" / "index.html").read_text()
    for section in ("tutorial", "howto", "explanation", "validation", "reference"):
        assert f'href="{section}/' in index, f"the front page links no {section} page"
    keys = (tmp_path / "html" / "reference" / "case_keys.html").read_text()
    assert "h_over_dx" in keys and "cr" in keys
