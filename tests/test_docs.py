"""The documentation runs: every ```python block of README.md and docs/guide.md, and every command of their
```console blocks.

Blocks of one file run in order in one namespace, in a scratch directory (what they write stays there). A
block may be skipped only with a stated reason: the fence ```python skip and a first line ``# skip: why``.
Console lines start with ``$ ``; those that call ``tribosweep`` are parsed by the real argument parser (so a
renamed flag breaks the test), and in docs/guide.md they are run, in order, after its Python blocks (the
guide keeps them small). Other commands (``make run``) are shown, not run.
"""

from __future__ import annotations

import pathlib
import re
import shlex

import pytest

from tribosweep import cli

ROOT = pathlib.Path(__file__).resolve().parents[1]
DOCS = {"README.md": ROOT / "README.md", "docs/guide.md": ROOT / "docs" / "guide.md"}
FENCE = re.compile(r"^```([^\n`]*)\n(.*?)^```\s*$", re.M | re.S)


def blocks(path: pathlib.Path, lang: str) -> list[tuple[int, str, str]]:
    """(line, info string, body) of every fenced block whose info string starts with ``lang``."""
    text = path.read_text()
    out = []
    for m in FENCE.finditer(text):
        info = m.group(1).strip()
        if info.split(" ")[0] == lang:
            out.append((text.count("\n", 0, m.start()) + 1, info, m.group(2)))
    return out


def commands(path: pathlib.Path) -> list[tuple[int, list[str]]]:
    """(line, argv after ``tribosweep``) of every ``$ tribosweep ...`` line of the console blocks."""
    out = []
    for line, _info, body in blocks(path, "console"):
        for k, row in enumerate(body.splitlines()):
            if not row.startswith("$ "):
                continue
            words = shlex.split(row[2:], comments=True)
            if words[:1] == ["tribosweep"]:
                out.append((line + 1 + k, words[1:]))
            elif words[:3] == ["python", "-m", "tribosweep"]:
                out.append((line + 1 + k, words[3:]))
    return out


def run_python_blocks(name: str, namespace: dict) -> None:
    found = blocks(DOCS[name], "python")
    assert found, f"{name} has no python blocks"
    for line, info, body in found:
        if info.split() != ["python"]:
            assert info.split() == ["python", "skip"], f"{name}:{line}: unknown fence info {info!r}"
            first = body.lstrip().splitlines()[0] if body.strip() else ""
            assert first.startswith("# skip:") and len(first) > len("# skip:") + 5, (
                f"{name}:{line}: a skipped block must say why on its first line ('# skip: ...')")
            continue
        try:
            exec(compile(body, f"{name}:{line}", "exec"), namespace)
        except Exception as e:  # name the block: the traceback's file name is the doc and its line
            raise AssertionError(f"{name}, block at line {line} failed: {type(e).__name__}: {e}") from e


@pytest.fixture
def scratch(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    yield tmp_path
    try:
        import matplotlib.pyplot as plt

        plt.close("all")  # xarray's .plot() draws with pyplot
    except ImportError:
        pass


def test_readme_python_blocks_run(scratch):
    pytest.importorskip("matplotlib")
    run_python_blocks("README.md", {"__name__": "__readme__"})


def test_guide_python_blocks_run_then_its_commands(scratch, capsys):
    pytest.importorskip("matplotlib")
    run_python_blocks("docs/guide.md", {"__name__": "__guide__"})
    cmds = commands(DOCS["docs/guide.md"])
    assert cmds, "the guide shows no command"
    for line, argv in cmds:
        code = cli.main(argv)
        err = capsys.readouterr().err
        assert code == 0, f"docs/guide.md:{line}: tribosweep {shlex.join(argv)} exited {code}: {err}"


@pytest.mark.parametrize("name", sorted(DOCS))
def test_every_command_line_parses(name, capsys):
    cmds = commands(DOCS[name])
    assert cmds, f"{name} shows no tribosweep command"
    parser = cli.build_parser()
    for line, argv in cmds:
        try:
            args = parser.parse_args(cli._attach_negative_values(parser, argv))
        except SystemExit as e:  # --help exits 0; a bad line exits 2 after argparse printed why
            assert e.code == 0 and "--help" in argv, (
                f"{name}:{line}: tribosweep {shlex.join(argv)} does not parse: {capsys.readouterr().err}")
            continue
        assert args.command in cli.COMMANDS, f"{name}:{line}"


def test_the_block_reader_sees_skips_and_console_lines(tmp_path):
    doc = tmp_path / "d.md"
    doc.write_text("```python\nx = 1\n```\n\n```python skip\n# skip: needs a GPU\n```\n\n"
                   "```console\n$ tribosweep info a.nc   # a comment\n$ make run\nout\n```\n")  # fmt: skip
    assert [(b[0], b[1]) for b in blocks(doc, "python")] == [(1, "python"), (5, "python skip")]
    assert commands(doc) == [(10, ["info", "a.nc"])]
