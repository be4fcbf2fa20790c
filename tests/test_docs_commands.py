"""Every command of the tutorial and the how-to guides runs as its page says.

The convention the pages follow (docs/tutorial/*.md, docs/howto/*.md, every page there):

- A command is a line that starts with ``$ `` inside a fenced ``console`` block; a line
  ending with ``\\`` goes on on the next line. Blocks of any other language are not run.
- The lines after a command, up to the next command or the end of the block, are its
  output as the page shows it. Each shown line must appear in what the command prints
  (stdout and stderr together) as a whole line, in the same order; other lines may come
  between them (a progress line, a compile notice). Text must match exactly (runs of
  blanks count as one), numbers within 5 % (1e-4 absolute); ``...`` stands for any text.
  Wall time, rates and memory (a number followed by ``s wall``, ``particle-steps/s`` or
  ``MB``) are not compared.
- A fenced block of another language whose first line is ``# file: PATH`` is a file the
  page has the reader write (a case.toml): it is written there, relative to the
  repository's root, before the commands after it run.
- Each command must exit with status 0. A page shows a refusal as
  ``$ sph run ... || echo "exit status $?"`` and the status as output.

``test_docs_commands`` (slow tier) runs every command with bash, in order, each how-to page
(and the tutorial's pages together, as each goes on from the one before) in a fresh
temporary directory that holds copies of the repository's ``cases/`` and ``examples/``
(without outputs) and links to its other folders (``postprocessing/`` ...), so a page
starts from a clean checkout and writes nothing into the repository. Not run:
``pip install`` lines (sphcore is installed for the tests: ``pip install ./examples/X``
is done by putting X's package and its entry points on the path) and the GUI steps in
:data:`NOT_RUN`. ``test_docs_sph_commands`` (fast tier) parses every ``sph`` command of
the pages with sph's own parser and, for ``sph run`` and ``sph check`` of a case the
repository holds or the page writes, runs ``sph check`` with the same options (``sph
sweep`` with ``--dry-run``, ``sph options`` as it is): a renamed option, a case directory
or key that no longer exists fails it in seconds.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted((ROOT / "docs" / "tutorial").glob("*.md")) + sorted((ROOT / "docs" / "howto").glob("*.md"))

#: commands that are shown but not run, with the reason: GUI steps
NOT_RUN = {
    "paraview": "a GUI",
}
#: output that changes from run to run: a number followed by one of these is not compared
VOLATILE = re.compile(r"(?:\d[\d.eE+-]*)(?=\s*(?:s wall|particle-steps/s|MB\b))")
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
# copied into each page's directory: the folders a page writes into (everything else is linked)
COPIED = ("cases", "examples")
LEFT_OUT = shutil.ignore_patterns("output*", "sweep*", "__pycache__", "build", "*.egg-info", "*.nbi", "*.nbc")


@dataclass
class Command:
    page: str
    line: int  # 1-based line of the page where the command starts
    text: str
    output: list[str] = field(default_factory=list)
    write: tuple[str, str] | None = None  # a file the page writes: (path, content)

    def __str__(self):
        return f"{self.page}:{self.line}: $ {self.text}"


def commands(page: Path) -> list[Command]:
    """The commands of a page's ```console blocks, in order, each with its shown output,
    and the files it writes (``# file: PATH`` blocks) where they come."""
    out: list[Command] = []
    fence = None
    cmd = None
    lines = page.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        if fence is None:
            m = re.match(r"^(`{3,}|~{3,})\s*\{?([\w-]+)\}?\s*$", stripped)
            if m:
                fence = (m.group(1), m.group(2))
                f = re.match(r"^#\s*file:\s*(\S+)\s*$", lines[i + 1].strip()) if i + 1 < len(lines) else None
                if f and fence[1] != "console":
                    body = []
                    j = i + 2
                    while j < len(lines) and not (lines[j].strip().startswith(fence[0])
                                                  and lines[j].strip().strip(fence[0][0]) == ""):
                        body.append(lines[j])
                        j += 1
                    out.append(Command(page.relative_to(ROOT).as_posix(), i + 2, f"(write {f.group(1)})",
                                       write=(f.group(1), "\n".join(body) + "\n")))
            i += 1
            continue
        if stripped.startswith(fence[0]) and stripped.strip(fence[0][0]) == "":
            fence, cmd = None, None
            i += 1
            continue
        if fence[1] != "console":
            i += 1
            continue
        if line.startswith("$ "):
            start = i
            text = line[2:]
            while text.endswith("\\") and i + 1 < len(lines):
                i += 1
                text = text[:-1] + " " + lines[i].strip()
            cmd = Command(page.relative_to(ROOT).as_posix(), start + 1, " ".join(text.split()))
            out.append(cmd)
        elif cmd is not None and stripped:
            cmd.output.append(line)
        i += 1
    return out


def _pieces(line: str) -> list:
    """A shown or printed line as text and numbers (volatile numbers and ``...`` as None)."""
    line = VOLATILE.sub("...", " ".join(line.split()))
    pieces: list = []
    for part in re.split(r"(\.\.\.)", line):
        if part == "...":
            pieces.append(None)
            continue
        pos = 0
        for m in NUMBER.finditer(part):
            if m.start() > pos:
                pieces.append(part[pos:m.start()])
            pieces.append(float(m.group()))
            pos = m.end()
        if pos < len(part):
            pieces.append(part[pos:])
    return pieces


def _regex(shown: list) -> re.Pattern:
    """A pattern for a printed line: the shown text literally, numbers and ``...`` as groups."""
    parts = []
    for p in shown:
        if p is None:
            parts.append(".*?")
        elif isinstance(p, float):
            parts.append(f"({NUMBER.pattern})")
        else:
            parts.append(r"\s*".join(re.escape(w) for w in p.split(" ")))
    return re.compile("".join(parts))


def line_matches(shown: str, printed: str) -> bool:
    pieces = _pieces(shown)
    m = _regex(pieces).fullmatch(" ".join(printed.split()))
    if m is None:
        return False
    numbers = [p for p in pieces if isinstance(p, float)]
    # a run prints the same figures on any machine (the same bits on any thread count): the
    # allowance is for the last digits a library version may move, not for a changed result
    return all(float(got) == pytest.approx(want, rel=0.01, abs=1e-4) for want, got in zip(numbers, m.groups()))


def missing_output(shown: list[str], printed: str) -> str | None:
    """The first shown line not found, in order, in the printed text (None: all found)."""
    rest = printed.splitlines()
    for want in shown:
        for k, got in enumerate(rest):
            if line_matches(want, got):
                rest = rest[k + 1:]
                break
        else:
            return want
    return None


def _not_run(cmd: Command) -> str | None:
    if cmd.write is not None:
        return None
    words = cmd.text.split()
    if words[:2] == ["pip", "install"] or words[:4] == ["python", "-m", "pip", "install"]:
        return "install"
    return NOT_RUN.get(words[0])


def _local_package(cmd: Command, cwd: Path) -> Path | None:
    """The folder of ``pip install [-e] ./path`` when it is a local package with a pyproject.toml."""
    if _not_run(cmd) != "install":
        return None
    words = [w for w in shlex.split(cmd.text) if w not in ("-e", "--editable")]
    if len(words) >= 3:
        path = cwd / words[-1]
        if (path / "pyproject.toml").is_file():
            return path
    return None


def stage_package(src: Path, site: Path) -> None:
    """What ``pip install src`` gives sphcore: the package importable and its entry points
    found (a .dist-info with entry_points.txt in ``site``, which goes on the path)."""
    project = tomllib.loads((src / "pyproject.toml").read_text())["project"]
    name = project["name"].replace("-", "_")
    info = site / f"{name}-{project.get('version', '0')}.dist-info"
    info.mkdir(parents=True, exist_ok=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {project['name']}\n"
                                   f"Version: {project.get('version', '0')}\n")
    lines = []
    for group, eps in project.get("entry-points", {}).items():
        lines.append(f"[{group}]")
        lines += [f"{k} = {v}" for k, v in eps.items()]
    (info / "entry_points.txt").write_text("\n".join(lines) + "\n")
    for pkg in src.iterdir():
        if (pkg / "__init__.py").is_file() and not (site / pkg.name).exists():
            shutil.copytree(pkg, site / pkg.name, ignore=LEFT_OUT)


def workdir(tmp: Path) -> Path:
    """A directory laid out like the repository: cases/ and examples/ copied, the rest linked."""
    work = tmp / "repo"
    work.mkdir()
    for entry in ROOT.iterdir():
        if entry.name.startswith(".") or entry.name in ("tests",):
            continue
        if entry.name in COPIED:
            shutil.copytree(entry, work / entry.name, ignore=LEFT_OUT)
        else:
            (work / entry.name).symlink_to(entry)
    return work


ALL = [(page, cmd) for page in PAGES for cmd in commands(page)]


def test_the_pages_have_commands():
    """The convention is in use: the tutorial and every how-to page run commands."""
    assert PAGES, "no pages in docs/tutorial or docs/howto"
    for page in PAGES:
        if page.name == "index.md" and page.parent.name == "howto":
            continue
        assert commands(page), f"{page.relative_to(ROOT)}: no ```console block with a `$ ` command"


def test_output_matching():
    """The matching rule on the lines the pages show."""
    assert line_matches("x: t = 0.3 s, 5579 steps, 4.08 s wall, 3.55e+06 particle-steps/s, peak memory 176 MB",
                        "x:  t = 0.3 s, 5600 steps, 9.1 s wall, 1e5 particle-steps/s, peak memory 1760 MB")
    assert not line_matches("x: 5579 steps", "x: 6579 steps")
    assert not line_matches("err_cruchaga_0.20s 0.0723", "err_cruchaga_0.20s 0.0745")  # 3 % off: a changed result
    assert not line_matches("5579 steps", "x: 5579 steps")  # a shown line is a whole printed line
    assert line_matches("ok; output: .../cases/dam_break/output", "ok; output: /tmp/x/cases/dam_break/output")
    assert line_matches("P1: max 39889.7 Pa -> run/probe_P1.png", "P1: max 40100 Pa -> run/probe_P1.png")
    assert not line_matches("exit status 2", "exit status 0")
    assert missing_output(["a 1", "b 2"], "a 1\nprogress\nb 2.01\n") is None
    assert missing_output(["b 2", "a 1"], "a 1\nb 2\n") == "a 1"


def _sph_argv(text: str) -> list[list[str]]:
    """The argument lists of every ``sph`` call in a shell command line."""
    lex = shlex.shlex(text, posix=True, punctuation_chars=True)
    lex.whitespace_split = True
    calls, cur = [], []
    for tok in lex:
        if tok in ("&&", "||", "|", ";", "(", ")", ">", ">>", "2>", "&"):
            calls.append(cur)
            cur = []
        else:
            cur.append(tok)
    calls.append(cur)
    return [c[1:] for c in calls if c and c[0] == "sph"]


@pytest.fixture(scope="module")
def staged(tmp_path_factory):
    """The pages' local packages (examples/plugin_template), importable here as after pip install."""
    site = tmp_path_factory.mktemp("site")
    for page, cmd in ALL:
        pkg = _local_package(cmd, ROOT)
        if pkg is not None:
            stage_package(pkg, site)
    return site


def test_docs_sph_commands(staged, tmp_path, monkeypatch, capsys):
    """Every sph command of the pages parses, and the case it runs passes sph check with the
    same options (the repository's cases, and those the page writes in a ``# file:`` block)."""
    from sphcore import cli
    from sphcore.plugin import pluginhost

    monkeypatch.syspath_prepend(str(staged))
    pluginhost.refresh()
    parser = cli._parser()
    checked = 0
    try:
        for page in PAGES:
            work = tmp_path / page.stem
            work.mkdir()
            for name in COPIED:
                (work / name).symlink_to(ROOT / name)  # read only: sph check writes nothing
            monkeypatch.chdir(work)
            for cmd in commands(page):
                if cmd.write is not None:
                    (work / cmd.write[0]).parent.mkdir(parents=True, exist_ok=True)
                    (work / cmd.write[0]).write_text(cmd.write[1], encoding="utf-8")
                    continue
                for argv in _sph_argv(cmd.text):
                    try:
                        args = parser.parse_args(argv)
                    except SystemExit as e:
                        assert e.code == 0, f"{cmd}: sph refuses the command line"
                        continue
                    refusal = "||" in cmd.text  # a page showing what sph refuses: parsed only
                    if args.command == "options":
                        assert cli.main(argv) == 0, f"{cmd}: {capsys.readouterr().err}"
                    elif args.command in ("run", "check", "sweep") and (work / args.case_dir / "case.toml").is_file():
                        if refusal:
                            continue
                        check = ["check", args.case_dir, *[f"--set={s}" for s in args.overrides]]
                        check += [] if args.t_end is None else ["--t-end", str(args.t_end)]
                        if args.command == "sweep":
                            check = argv if "--dry-run" in argv else [*argv, "--dry-run"]
                        rc = cli.main(check)
                        assert rc == 0, f"{cmd}: sph {' '.join(check)}: exit {rc}: {capsys.readouterr().err}"
                        checked += 1
                    elif args.command in ("run", "check", "sweep"):  # a case the page makes with a command
                        made = [c.text for c in commands(page) if c.line < cmd.line and not c.write]
                        top = args.case_dir.rstrip("/").split("/")[0]
                        assert any(top in t for t in made), \
                            f"{cmd}: no case {args.case_dir}, and the page does not make it before"
    finally:
        pluginhost.refresh()
    assert checked > 0


def _run_pages(pages: list[Path], tmp_path: Path) -> None:
    work = workdir(tmp_path)
    site = tmp_path / "site"
    site.mkdir()
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONUNBUFFERED="1", PYTHONPATH=os.pathsep.join(
        [str(site), *filter(None, [os.environ.get("PYTHONPATH")])]))
    env.pop("PYTHONSTARTUP", None)
    bindir = Path(sys.executable).parent  # `sph` and `python` of this environment first
    env["PATH"] = os.pathsep.join([str(bindir), env.get("PATH", "")])
    for cmd in [c for page in pages for c in commands(page)]:
        if cmd.write is not None:
            path = work / cmd.write[0]
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(cmd.write[1], encoding="utf-8")
            continue
        if _not_run(cmd):
            pkg = _local_package(cmd, work)
            if pkg is not None:
                stage_package(pkg, site)
            continue
        start = time.perf_counter()
        p = subprocess.run(["bash", "-c", cmd.text], cwd=work, env=env, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, timeout=600)
        print(f"{time.perf_counter() - start:6.1f} s  {cmd}")
        printed = p.stdout
        assert p.returncode == 0, f"{cmd}\nexit status {p.returncode}\n{printed[-3000:]}"
        lost = missing_output(cmd.output, printed)
        assert lost is None, f"{cmd}\nthe page shows\n    {lost}\nbut the command printed\n{printed[-3000:]}"


#: the pages run as one sequence, in one directory: each tutorial page goes on from the one before
SEQUENCES = {"tutorial": sorted((ROOT / "docs" / "tutorial").glob("*.md"))}
SEQUENCES.update({f"howto/{p.name}": [p] for p in sorted((ROOT / "docs" / "howto").glob("*.md"))})


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SEQUENCES))
def test_docs_commands(name, tmp_path):
    """Every command of the page (the tutorial: of its pages in order), in a clean copy of the
    cases: exit status 0, and the output the page shows."""
    pages = SEQUENCES[name]
    if not any(commands(p) for p in pages):
        pytest.skip("no commands")
    _run_pages(pages, tmp_path)
