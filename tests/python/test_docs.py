"""The pages a newcomer reads (README.md, docs/*.md) show only what exists (issue 32).

Every command they show is checked against the thing it runs:
- `bash scripts/NAME.sh --opt`: the script exists; an option is one the script names, or one of the
  `wetclutch` subcommand it ends in (`exec .venv/bin/wetclutch SUB ... "$@"`);
- `.venv/bin/wetclutch SUB ...` (or `wetclutch SUB`): in a code block the whole line is parsed by the CLI's
  own argparse parser (wetclutch.cli.build_parser: subcommand, options, choices, values); in running text
  the subcommand and every `--option` must exist;
- `build/PRESET/src/DIR/PROGRAM --opt`: PRESET is a CMake configure preset, PROGRAM an add_executable of
  src/DIR, and each option is one its source parses (`"--opt"` or getopt's `{"opt",`);
- `cmake --preset P`, `cmake --build --preset P`, `ctest --preset P`: P is such a preset;
- `python -m MODULE` (`pytest` aside): the module is a file of tools/; `python -m pytest PATH`: PATH exists;
- a code block names its language (sh for commands, text for a picture);
- every repository path in code (scripts/, hil/, tools/, tests/, src/, include/, bench/, lut/, cmake/,
  docs/) exists; out/ and build/ are what commands write, not checked.
Every relative link resolves to a file or folder, and every #anchor to a heading of its page (GitHub's
anchors). test_the_check_finds_what_is_broken feeds it a page with one mistake of each kind.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import re
import shlex
from pathlib import Path

import pytest

from wetclutch.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
AUDIENCE_PAGES = ("integrating.md", "calibrating.md", "shift-control.md", "model.md", "results.md")
README_MAX_LINES = 250

SHELL_LANGS = {"sh", "bash", "shell", "console"}   # a block says its language: these are commands
REPO_DIRS = ("scripts", "hil", "tools", "tests", "src", "include", "bench", "lut", "cmake", "docs")
PATH_RE = re.compile(r"(?<![\w./-])((?:%s)/[\w.+/-]*[\w/])" % "|".join(REPO_DIRS))
FENCE_RE = re.compile(r"^\s*(```+|~~~+)\s*([\w+-]*)")
LINK_RE = re.compile(r"(?<!!)\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)\)|!\[[^\]]*\]\(([^)\s]+)\)")
INLINE_RE = re.compile(r"(`+)(.+?)\1")


# --------------------------------------------------------------------------- reading a page
def _split_page(text: str):
    """(blocks, prose): blocks as (line number, language, [lines]); prose as (line number, line) outside them."""
    blocks, prose = [], []
    fence = None
    for number, line in enumerate(text.splitlines(), 1):
        m = FENCE_RE.match(line)
        if fence is None and m:
            fence, block = m.group(1), (number, m.group(2).lower(), [])
        elif fence is not None and line.strip().startswith(fence[0] * len(fence)) and not line.strip().strip(fence[0]):
            blocks.append(block)
            fence = None
        elif fence is not None:
            block[2].append(line)
        else:
            prose.append((number, line))
    return blocks, prose


def _inline_spans(prose):
    for number, line in prose:
        for m in INLINE_RE.finditer(line):
            yield number, m.group(2).strip()


def _shell_commands(lines: list[str]):
    """Commands of a shell block: continuation lines joined, comments and prompts dropped, split at ;, &&, ||, |."""
    joined, buf = [], ""
    for line in lines:
        if line.rstrip().endswith("\\"):
            buf += line.rstrip()[:-1] + " "
            continue
        joined.append(buf + line)
        buf = ""
    if buf:
        joined.append(buf)
    for line in joined:
        line = re.sub(r"^\s*\$\s+", "", line)
        line = re.sub(r"(^|\s)#.*$", "", line).strip()
        for part in re.split(r"\s*(?:&&|\|\||;|\|)\s*", line):
            part = re.sub(r"\s*&$", "", part).strip()
            if part:
                yield part


def _tokens(command: str) -> list[str]:
    tokens = shlex.split(command)
    out, skip = [], False
    for t in tokens:          # redirections and their targets are the shell's
        if skip:
            skip = False
            continue
        if t in ("<", ">", ">>", "2>", "2>&1"):
            skip = t != "2>&1"
            continue
        if re.match(r"^\d?>>?\S|^<\S", t):
            continue
        out.append(t)
    return out


# --------------------------------------------------------------------------- what a command may name
def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    for action in parser._actions:   # noqa: SLF001 - argparse keeps its subcommands here
        if isinstance(action, argparse._SubParsersAction):   # noqa: SLF001
            return dict(action.choices)
    raise AssertionError("wetclutch.cli.build_parser has no subcommands")


SUBPARSERS = _subparsers()


def _presets() -> dict[str, set[str]]:
    data = json.loads((ROOT / "CMakePresets.json").read_text(encoding="utf-8"))
    return {kind: {p["name"] for p in data.get(f"{kind}Presets", [])} for kind in ("configure", "build", "test")}


PRESETS = _presets()


def _options(tokens: list[str]) -> list[str]:
    return [t.split("=", 1)[0] for t in tokens if t.startswith("--") and len(t) > 2]


def _check_wetclutch(tokens: list[str], whole: bool) -> list[str]:
    if not tokens or tokens[0].startswith("-"):
        return [] if tokens and tokens[0] in ("-h", "--help") else ["`wetclutch` without a subcommand"]
    sub = tokens[0]
    if sub not in SUBPARSERS:
        return [f"`wetclutch {sub}`: no such subcommand (has: {', '.join(sorted(SUBPARSERS))})"]
    known = {s for a in SUBPARSERS[sub]._actions for s in a.option_strings}   # noqa: SLF001
    problems = [f"`wetclutch {sub} {o}`: no such option" for o in _options(tokens[1:]) if o not in known]
    if whole and not problems:
        err = io.StringIO()
        try:
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                build_parser().parse_args(tokens)
        except SystemExit as e:
            if e.code:
                message = err.getvalue().strip().splitlines()[-1:] or ["exit " + str(e.code)]
                problems.append(f"`wetclutch {' '.join(tokens)}`: the CLI refuses it: {message[0]}")
    return problems


def _check_script(path: str, args: list[str]) -> list[str]:
    script = ROOT / path
    if not script.is_file():
        return [f"`{path}`: no such script"]
    text = script.read_text(encoding="utf-8")
    m = re.search(r'exec \.venv/bin/wetclutch ([\w-]+) .*"\$@"', text)
    sub_options = set()
    if m and m.group(1) in SUBPARSERS:
        sub_options = {s for a in SUBPARSERS[m.group(1)]._actions for s in a.option_strings}   # noqa: SLF001
    return [f"`{path} {o}`: the script takes no such option" for o in _options(args)
            if o not in sub_options and not re.search(r"(?<![\w-])%s(?![\w-])" % re.escape(o), text)]


def _check_program(path: str, args: list[str]) -> list[str]:
    m = re.fullmatch(r"build/([\w-]+)/src/(\w+)/(\w+)", path)
    if not m:
        return [f"`{path}`: not a program of the build (build/PRESET/src/DIR/NAME)"]
    preset, folder, name = m.groups()
    problems = [] if preset in PRESETS["configure"] else [f"`{path}`: no configure preset {preset}"]
    cmake = ROOT / "src" / folder / "CMakeLists.txt"
    if not cmake.is_file() or not re.search(r"add_executable\(%s\s" % re.escape(name), cmake.read_text()):
        return problems + [f"`{path}`: src/{folder}/CMakeLists.txt builds no {name}"]
    source = (ROOT / "src" / folder / f"{name}.c").read_text(encoding="utf-8")
    if "wc_tcu_gearbox_option(" in source:   # the transmission's options: one parser for wc_tcu and wc_replay
        source += (ROOT / "src" / "port" / "wc_tcu_gearbox.c").read_text(encoding="utf-8")
    for o in _options(args):
        if f'"{o}"' not in source and f'{{"{o[2:]}",' not in source:
            problems.append(f"`{name} {o}`: src/{folder}/{name}.c parses no such option")
    return problems


def _check_tokens(tokens: list[str], whole: bool) -> list[str]:
    """Problems of one command (its tokens), [] when it is not one this check knows."""
    if not tokens:
        return []
    head, args = tokens[0], tokens[1:]
    if head == "bash" and args:
        head, args = args[0], args[1:]
    if head in ("wetclutch", ".venv/bin/wetclutch"):
        return _check_wetclutch(args, whole)
    if head.endswith(".sh") and head.split("/")[0] in REPO_DIRS:
        if "--" in args:   # hil/vcan_run.sh -- CMD: the command it runs is checked as a command
            k = args.index("--")
            return _check_script(head, args[:k]) + _check_tokens(args[k + 1:], whole)
        return _check_script(head, args)
    if head.startswith("build/"):
        return _check_program(head, args)
    if head in ("cmake", "ctest") and "--preset" in args[:-1]:
        preset = args[args.index("--preset") + 1]
        kind = "test" if head == "ctest" else "build" if "--build" in args else "configure"
        return [] if preset in PRESETS[kind] else [f"`{' '.join(tokens)}`: no {kind} preset {preset}"]
    if re.fullmatch(r"(\.venv/bin/)?python3?", head) and args[:1] == ["-m"] and len(args) > 1:
        if args[1] == "pytest":
            paths = [a.split("::")[0] for a in args[2:] if not a.startswith("-")]
            return [f"`{p}`: no such test path" for p in paths if not (ROOT / p).exists()]
        module = ROOT / "tools" / Path(*args[1].split("."))
        if not (module.with_suffix(".py").is_file() or (module / "__main__.py").is_file()):
            return [f"`python -m {args[1]}`: no such module in tools/"]
    return []


def _check_paths(number: int, code: str) -> list[str]:
    problems = []
    for m in PATH_RE.finditer(code):
        path = m.group(1).split("::")[0]
        if not (ROOT / path).exists():
            problems.append(f"line {number}: `{path}`: no such file or folder")
    return problems


COMMAND_HEADS = ("bash ", "wetclutch ", ".venv/bin/", "build/", "cmake --", "ctest --", "python -m ",
                 "python3 -m ")


def command_problems(page: Path) -> list[str]:
    blocks, prose = _split_page(page.read_text(encoding="utf-8"))
    problems = []
    for number, lang, lines in blocks:
        for k, line in enumerate(lines, 1):
            problems += _check_paths(number + k, line)
        if not lang:
            problems.append(f"block at line {number}: no language (sh for commands, text for a picture)")
        if lang not in SHELL_LANGS:
            continue
        for command in _shell_commands(lines):
            try:
                tokens = _tokens(command)
            except ValueError as e:
                problems.append(f"block at line {number}: `{command}`: {e}")
                continue
            problems += [f"block at line {number}: {p}" for p in _check_tokens(tokens, whole=True)]
    for number, span in _inline_spans(prose):
        problems += _check_paths(number, span)
        if span.startswith(COMMAND_HEADS):
            try:
                tokens = _tokens(span)
            except ValueError:
                continue
            problems += [f"line {number}: {p}" for p in _check_tokens(tokens, whole=False)]
    return problems


# --------------------------------------------------------------------------- links
def _anchor(heading: str) -> str:
    """GitHub's anchor of a heading: markup dropped, lower case, punctuation out, spaces to hyphens."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)
    text = re.sub(r"[`*_]{1,3}(?=\S)|(?<=\S)[`*_]{1,3}", "", text)
    return re.sub(r"[^\w\- ]", "", text.strip().lower()).replace(" ", "-")


def anchors(page: Path) -> set[str]:
    _, prose = _split_page(page.read_text(encoding="utf-8"))
    seen: dict[str, int] = {}
    out = set()
    for _, line in prose:
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not m:
            continue
        base = _anchor(m.group(1))
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.add(base if n == 0 else f"{base}-{n}")
    return out


def link_problems(page: Path) -> list[str]:
    _, prose = _split_page(page.read_text(encoding="utf-8"))
    problems = []
    for number, line in prose:
        line = INLINE_RE.sub("", line)
        for m in LINK_RE.finditer(line):
            target = m.group(1) or m.group(2)
            if re.match(r"^[a-z][\w+.-]*:", target):   # http:, https:, mailto:: not fetched
                continue
            path, _, anchor = target.partition("#")
            dest = (page.parent / path).resolve() if path else page
            if not dest.exists():
                problems.append(f"line {number}: link to {target}: {path} does not exist")
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                problems.append(f"line {number}: link to {target}: {dest.name} has no heading #{anchor}")
            elif anchor and dest.suffix != ".md":
                problems.append(f"line {number}: link to {target}: an anchor into a file that is not a page")
    return problems


# --------------------------------------------------------------------------- the tests
def _id(page: Path) -> str:
    return str(page.relative_to(ROOT))


def test_the_pages_are_there():
    assert (ROOT / "README.md").is_file()
    missing = [p for p in AUDIENCE_PAGES if not (ROOT / "docs" / p).is_file()]
    assert not missing, f"docs pages missing: {missing}"
    lines = len((ROOT / "README.md").read_text(encoding="utf-8").splitlines())
    assert lines <= README_MAX_LINES, f"README.md has {lines} lines (at most {README_MAX_LINES})"


def test_the_readme_links_every_page():
    readme = ROOT / "README.md"
    targets = {(readme.parent / (m.group(1) or m.group(2)).partition("#")[0]).resolve()
               for _, line in _split_page(readme.read_text(encoding="utf-8"))[1]
               for m in LINK_RE.finditer(INLINE_RE.sub("", line))}
    unlinked = [p for p in AUDIENCE_PAGES if (ROOT / "docs" / p).resolve() not in targets]
    assert not unlinked, f"README.md does not link {unlinked}"


@pytest.mark.parametrize("page", PAGES, ids=_id)
def test_every_command_shown_exists(page):
    problems = command_problems(page)
    assert not problems, f"{_id(page)}:\n" + "\n".join(problems)


@pytest.mark.parametrize("page", PAGES, ids=_id)
def test_every_link_resolves(page):
    problems = link_problems(page)
    assert not problems, f"{_id(page)}:\n" + "\n".join(problems)


def test_the_check_finds_what_is_broken(tmp_path):
    """One mistake of each kind on a page of a docs/ folder beside a README (in tmp_path)."""
    (tmp_path / "docs").mkdir()
    (tmp_path / "README.md").write_text("# The project\n", encoding="utf-8")
    (tmp_path / "docs" / "results.md").write_text("# Results\n", encoding="utf-8")
    page = tmp_path / "docs" / "page.md"
    page.write_text("\n".join([
        "# A page",
        "## Its second heading",
        "[fine](../README.md) [fine too](#its-second-heading) [fine](results.md#results)",
        "[no such page](no-such-page.md)",
        "[no such heading](#no-such-heading)",
        "[no such heading there](../README.md#no-such-heading)",
        "See `scripts/no_such_script.sh` and `wetclutch lut --no-such-option`.",
        "```sh",
        "bash scripts/test.sh --quick",
        ".venv/bin/wetclutch lut tools/calibrations/table1.toml --out lut",
        "bash scripts/test.sh --no-such-option",
        ".venv/bin/wetclutch no-such-subcommand",
        ".venv/bin/wetclutch identify everything out/bench_campaign",
        "bash hil/vcan_run.sh --vm -- build/host-release/src/port/wc_tcu --iface vcan0 --no-such-option",
        "build/host-release/src/port/no_such_program --help",
        "cmake --preset no-such-preset",
        ".venv/bin/python -m wetclutch.no_such_module",
        "```",
        "```",
        "a block without a language",
        "```",
    ]) + "\n", encoding="utf-8")
    found = "\n".join(link_problems(page) + command_problems(page))
    expected = ["no-such-page.md does not exist", "has no heading #no-such-heading",
                "README.md has no heading #no-such-heading", "scripts/no_such_script.sh",
                "`wetclutch lut --no-such-option`: no such option", "`scripts/test.sh --no-such-option`",
                "`wetclutch no-such-subcommand`: no such subcommand", "invalid choice: 'everything'",
                "`wc_tcu --no-such-option`", "builds no no_such_program", "no configure preset no-such-preset",
                "no such module", "no language"]
    missed = [e for e in expected if e not in found]
    assert not missed, f"the check missed {missed}; it found:\n{found}"
    assert found.count("\n") + 1 == len(expected), f"more found than broken:\n{found}"
