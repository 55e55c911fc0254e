"""The examples the package shows its users run as written: the
``satagraph`` command lines of every subcommand's help (epilog, and the
back-quoted ones of its description and option help) and of the CLI
modules' ``Examples::`` blocks parse, and the cheap docstring examples run
on stand-in files, the values their comments claim (``expr  # 'value'``)
included (the runs are marked slow: ``make test-slow``; the parses and the
check that every example is run or excused are not). README snippets are
tests/test_readme.py's."""
from __future__ import annotations

import argparse
import ast
import doctest
import importlib
import re
import shlex
import textwrap
from functools import lru_cache
from pathlib import Path
from typing import Dict, Iterator, List, Tuple

import pytest

import satagraph
from satagraph.cli import build_parser, parse_args

PACKAGE = Path(satagraph.__file__).resolve().parent

#: Docstring examples run here: ``file[:qualname]`` -> the namespace they
#: run in: ``"module"`` (the names of the module they document, as its
#: functions' examples assume) or ``"fresh"`` (they import what they use).
RUN: Dict[str, str] = {
    "_lazy.py:lazy_exports": "module",
    "sides.py": "module",
    "semantics/foreign.py": "module",
    "semantics/__init__.py": "fresh",
    "semantics/reference_rigs.py": "fresh",
    "semantics/factory.py:register_text_encoder": "fresh",
    "nn/layers/local_conv.py:register_local_conv": "fresh",
    "transforms/augment.py:SkeletonAugment": "module",
    "datasets/mirror.py:mirror_text": "module",
    "datasets/reverse.py:reverse_text": "module",
    "datasets/zoo/endless.py": "module",
    "datasets/zoo/dialects.py": "module",
    "datasets/zoo/__init__.py": "fresh",
    "viz/render.py": "fresh",
}
#: Subcommands whose help examples also run (seconds, on stand-in files).
RUN_HELP = ("inspect", "convert", "render", "cache")
#: Docstring examples not run here, and why.
NOT_RUN: Dict[str, str] = {
    "datasets/captions.py": "needs ../shared/data: test_captions_example",
    "experiment/demo.py": "trains a model for a minute",
    "experiment/sweep.py": "trains two models",
    "experiment/registry.py": "shows how the built-in modules register themselves",
    "transforms/mirror_average.py": "a sketch: '...' stands for decoding",
    "cli/render.py": "command lines: test_cli_docstring_examples_parse",
    "cli/zoo.py": "command lines: test_cli_docstring_examples_parse",
    "cli/tags.py": "command lines: test_cli_docstring_examples_parse",
    "cli/cache.py": "command lines: test_cli_docstring_examples_parse",
    "cli/sweep.py": "command lines: test_cli_docstring_examples_parse",
}


# ------------------------------------------------------------- collecting
def example_blocks(doc: str) -> List[str]:
    """The code of every ``Example::`` / ``Examples::`` block of
    :obj:`doc`, dedented."""
    lines, out = doc.splitlines(), []
    for i, line in enumerate(lines):
        if re.fullmatch(r"\s*Examples?::\s*", line):
            indent, body = len(line) - len(line.lstrip()), []
            for text in lines[i + 1:]:
                if text.strip() and len(text) - len(text.lstrip()) <= indent:
                    break
                body.append(text)
            out.append(textwrap.dedent("\n".join(body)).strip("\n"))
    return out


def docstring_examples() -> Dict[str, List[str]]:
    """``file[:qualname]`` -> the example blocks of its docstring, for every
    module, class and function of the package (read, not imported; a copy of
    :func:`_docstring_examples`)."""
    return {key: list(blocks) for key, blocks in _docstring_examples().items()}


@lru_cache(maxsize=None)
def _docstring_examples() -> Dict[str, List[str]]:
    """:func:`docstring_examples`, parsed once a worker (0.7 s: every file
    of the package)."""
    found: Dict[str, List[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        nodes = [(tree, "")] + [(node, f":{node.name}") for node in ast.walk(tree)
                                if isinstance(node, (ast.FunctionDef, ast.ClassDef))]
        for node, name in nodes:
            blocks = example_blocks(ast.get_docstring(node) or "")
            if blocks:
                found[f"{path.relative_to(PACKAGE).as_posix()}{name}"] = blocks
    return found


def _module_of(key: str):
    path = key.split(":")[0][:-len(".py")].replace("/", ".")
    return importlib.import_module("satagraph." + path.replace(".__init__", "")
                                   if path != "__init__" else "satagraph")


def subparsers() -> Dict[str, argparse.ArgumentParser]:
    """Every ``satagraph`` subcommand's parser by name."""
    parser = build_parser()
    actions = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(actions[0].choices)


def help_commands() -> Iterator[Tuple[str, str]]:
    """``(subcommand, command line)`` of every example its help shows:
    the epilog's (``examples: A; B`` or one a line), and those of its
    description and option help: back-quoted, or closing the text after a
    colon (a back-quoted bare ``satagraph COMMAND`` is a name, not an
    example)."""
    for name, sub in subparsers().items():
        epilog = re.sub(r"^examples?:", "", (sub.epilog or "").strip())
        for line in re.split(r"[;|\n]", epilog):
            if line.strip():
                yield name, line.strip()
        texts = [sub.description or ""] + [a.help or "" for a in sub._actions]
        for text in texts:
            for line in (re.findall(r"`(satagraph [\w-]+ [^`]+)`", text)
                         + re.findall(r": (satagraph [\w-]+ [^`:]+?)\.?$", text)):
                yield name, line


def command_lines(code: str) -> List[List[str]]:
    """The ``satagraph`` command lines of a block, as argv lists
    (continuation lines joined, comments dropped)."""
    out = []
    for line in code.replace("\\\n", " ").splitlines():
        words = shlex.split(line, comments=True)
        if words and words[0] == "satagraph":
            out.append(words[1:])
    return out


# ---------------------------------------------------------------- running
def _claim(lines: List[str], node: ast.stmt):
    """The value the comment after an expression statement claims (on its
    last line, or alone on the next line), or ``None`` where it claims no
    Python literal (``# [J, 256]``) or elides part of it (``...``)."""
    rest = lines[node.end_lineno - 1][node.end_col_offset:].strip()
    if not rest and node.end_lineno < len(lines):
        rest = lines[node.end_lineno].strip()
    if not rest.startswith("#"):
        return None
    try:
        value = ast.literal_eval(rest[1:].strip())
    except (ValueError, SyntaxError):
        return None
    return None if "..." in rest else (value,)


def run_example(code: str, scope: dict, name: str) -> int:
    """Run :obj:`code` statement by statement in :obj:`scope`, checking
    that every expression equals the literal its comment claims; returns
    how many claims were checked."""
    lines, checked = code.splitlines(), 0
    for node in ast.parse(code).body:
        claim = _claim(lines, node) if isinstance(node, ast.Expr) else None
        compiled = compile(ast.Module([node], []) if claim is None else
                           ast.Expression(node.value), name,
                           "exec" if claim is None else "eval")
        value = eval(compiled, scope)
        if claim is not None:
            assert value == claim[0], (name, ast.unparse(node), value)
            checked += 1
    return checked


@pytest.fixture()
def stand_ins(tmp_path, monkeypatch) -> dict:
    """A temporary working folder holding ``walk.bvh`` (a zoo walk), and
    the names examples take as given (``rig``, ``motion``, ...); the
    plug-in registries restored afterwards."""
    from satagraph.datasets.zoo import generate_clip, zoo_rigs
    from satagraph.io import write_bvh
    from satagraph.nn.layers import local_conv
    from satagraph.semantics import factory
    monkeypatch.setattr(local_conv, "_BUILDERS", dict(local_conv._BUILDERS))
    monkeypatch.setattr(factory, "TEXT_ENCODERS", dict(factory.TEXT_ENCODERS))
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SATAGRAPH_CACHE", str(tmp_path / "cache"))
    rig = zoo_rigs(["quadruped"])[0]
    motion = generate_clip(rig, "walk", frames=40, seed=1)
    write_bvh(motion, "walk.bvh")
    return {"rig": rig, "motion": motion, "reconstruction": motion,
            "generate_clip": generate_clip}


# ------------------------------------------------------------------ tests
def test_every_docstring_example_is_run_or_excused():
    """A new ``Example::`` block is added to :data:`RUN` or
    :data:`NOT_RUN` (with why), never silently untested."""
    found = set(docstring_examples())
    assert found == set(RUN) | set(NOT_RUN), found ^ (set(RUN) | set(NOT_RUN))


@pytest.mark.slow
@pytest.mark.parametrize("key", sorted(RUN))
def test_docstring_example_runs(key, stand_ins):
    (code,) = docstring_examples()[key]
    scope = dict(vars(_module_of(key))) if RUN[key] == "module" else {}
    scope.update(stand_ins, __name__=_module_of(key).__name__)
    run_example(code, scope, key)
    if key == "datasets/zoo/dialects.py":  # names bound as the Motions they look like
        assert all(isinstance(scope[n], satagraph.Motion) for n in ("zup_cm", "odd"))


def test_claims_are_checked(stand_ins):
    """The claimed values are compared: a wrong one fails."""
    from satagraph.sides import side_of
    assert run_example('side_of("thigh.L")  # "left"\n', {"side_of": side_of}, "ok") == 1
    with pytest.raises(AssertionError):
        run_example('side_of("thigh.L")  # "right"\n', {"side_of": side_of}, "wrong")


@pytest.mark.parametrize("fn", ["window_spans", "continuation_spans"])
def test_doctest_examples(fn):
    from satagraph.nn.generators import codes
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    for test in doctest.DocTestFinder().find(getattr(codes, fn), fn, globs=vars(codes)):
        runner.run(test)
    assert runner.summarize(verbose=False).attempted >= 1
    assert runner.summarize(verbose=False).failed == 0


@pytest.mark.slow
def test_retargeter_doctest(stand_ins):
    """The :class:`~satagraph.pipelines.Retargeter` example, with the
    walk as the dog and two source paths."""
    from satagraph.pipelines import Retargeter
    Path("dog.bvh").write_bytes(Path("walk.bvh").read_bytes())
    Path("a.bvh").write_bytes(Path("walk.bvh").read_bytes())
    runner = doctest.DocTestRunner()
    for test in doctest.DocTestFinder().find(Retargeter, "Retargeter",
                                             globs={"paths": ["a.bvh", "walk.bvh"]}):
        runner.run(test)
    assert runner.summarize(verbose=False) == (0, 5)
    assert Path("a_dog.bvh").is_file() and Path("walk_dog.bvh").is_file()


def test_captions_example(shared_data, monkeypatch):
    """The captions module example, on the shared data: the first caption
    is the one its comment shows."""
    (code,) = docstring_examples()["datasets/captions.py"]
    claimed = re.search(r"Caption\(text='([^']+)'", code).group(1)
    code = code.replace("../shared/data", shared_data.as_posix())
    scope = dict(vars(_module_of("datasets/captions.py")))
    first = eval(ast.unparse(ast.parse(code).body[0]), scope)
    assert [c.text for c in first][0] == claimed and len(first) == 3
    run_example(code, scope, "datasets/captions.py")
    assert scope["clips"]


def test_help_examples_found():
    names = {name for name, _ in help_commands()}
    assert {"inspect", "convert", "demo", "zoo", "render", "cache", "train"} <= names


@pytest.mark.parametrize("name, line", list(help_commands()))
def test_help_examples_parse(name, line):
    """Every example a subcommand's ``--help`` shows parses as typed."""
    argv = shlex.split(line)
    assert argv[0] == "satagraph", line
    args = parse_args(build_parser(), argv[1:])
    assert args.command == argv[1] and args.func is not None


@pytest.mark.parametrize("key", sorted(k for k in NOT_RUN if k.startswith("cli/")))
def test_cli_docstring_examples_parse(key):
    """The command lines of the CLI modules' ``Examples::`` blocks parse
    as typed (a shell splits an unquoted ``NAME=two words``)."""
    (code,) = docstring_examples()[key]
    lines = command_lines(code)
    assert lines, key
    for argv in lines:
        args = parse_args(build_parser(), argv)
        assert args.command == argv[0] and args.func is not None


@pytest.mark.slow
def test_cheap_help_examples_run(stand_ins, capsys):
    """The help examples of :data:`RUN_HELP` run on stand-in files (a
    cache ``--dir`` outside the temporary folder is not touched)."""
    from satagraph.cli import main
    for name in ("in.bvh", "a.bvh", "b.bvh", "mocap/walk.bvh"):
        Path(name).parent.mkdir(exist_ok=True)
        Path(name).write_bytes(Path("walk.bvh").read_bytes())
    ran = 0
    for name, line in help_commands():
        argv = shlex.split(line)[1:]
        if name in RUN_HELP and "--dir" not in argv:
            assert main(argv) == 0, (line, capsys.readouterr().err)
            ran += 1
    assert ran >= 6 and Path("out.bvh").is_file() and Path("sheet.png").is_file()
