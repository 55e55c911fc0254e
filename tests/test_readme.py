"""Every code snippet of README.md runs as written on a fresh clone, without
``../shared/data``: the python blocks in order in one namespace, the
``satagraph`` command lines parsed (all) and run (the cheap ones), in a
temporary folder."""
from __future__ import annotations

import json
import re
import shlex
from pathlib import Path
from typing import List, Tuple

import pytest

from satagraph.cli import build_parser, main, parse_args

README = Path(__file__).resolve().parents[1] / "README.md"
#: Commands run (not only parsed): seconds on a CPU, no data, no checkpoint;
#: ``zoo`` only where it writes one clip per rig (``--clips 1``).
RUN = ("inspect", "convert", "tags", "zoo")


def blocks() -> List[Tuple[str, str]]:
    """``(language, code)`` of every fenced block, in order."""
    return re.findall(r"```(\w+)\n(.*?)```", README.read_text(), flags=re.S)


def command_lines(code: str) -> List[List[str]]:
    """The ``satagraph`` command lines of a bash block, as argv lists
    (continuation lines joined, comments dropped)."""
    out = []
    for line in code.replace("\\\n", " ").splitlines():
        words = shlex.split(line, comments=True)
        if words and words[0].endswith("satagraph"):
            out.append(words[1:])
    return out


def _runs(argv: List[str]) -> bool:
    small = argv[0] != "zoo" or "--clips" in argv and argv[argv.index("--clips") + 1] == "1"
    return argv[0] in RUN and small


def _fake_answer(argv: List[str]) -> None:
    """A language model's answer for ``tags FILE --import ANSWER``: the
    descriptions satagraph itself gives (stands in for the LLM)."""
    from satagraph.semantics import describe_joints
    from satagraph.io import read_bvh
    skeleton = read_bvh(argv[1]).skeleton
    answer = dict(zip(skeleton.names, describe_joints(skeleton)))
    Path(argv[argv.index("--import") + 1]).write_text(json.dumps(answer))


def test_readme_has_snippets():
    kinds = [lang for lang, _ in blocks()]
    assert kinds.count("python") >= 4 and kinds.count("bash") >= 5


def test_readme_snippets_run(tmp_path, monkeypatch, capsys):
    from satagraph.nn.layers import local_conv
    monkeypatch.setattr(local_conv, "_BUILDERS", dict(local_conv._BUILDERS))  # its "graph"
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SATAGRAPH_CACHE", str(tmp_path / "cache"))
    scope: dict = {"__name__": "__main__"}  # as a script runs: its main guard too
    for number, (lang, code) in enumerate(blocks()):
        if lang == "python":
            exec(compile(code, f"README.md block {number}", "exec"), scope)
            continue
        for argv in command_lines(code):
            args = parse_args(build_parser(), argv)  # every line parses
            assert args.func is not None
            if not _runs(argv):
                continue
            if "--import" in argv:
                _fake_answer(argv)
            assert main(argv) == 0, (number, argv, capsys.readouterr().err)
    assert Path("runs/my_module/checkpoints/last.ckpt").is_file()
    assert json.loads(Path("crab_tags.json").read_text())


def _anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped,
    spaces as hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.lower()).replace(" ", "-")


def test_readme_contents_list_every_section():
    """The contents list at the top links every ``##``/``###`` heading
    outside code blocks, in order, by its anchor (a section added without
    its line, or renamed, fails)."""
    text = re.sub(r"```.*?```", "", README.read_text(), flags=re.S)
    headings = re.findall(r"^#{2,3} (.+)$", text, flags=re.M)
    listed = re.findall(r"^ *- \[(.+)\]\(#([\w\-]+)\)$", text, flags=re.M)
    assert [title for title, _ in listed] == headings
    assert [anchor for _, anchor in listed] == [_anchor(h) for h in headings]


def test_readme_speaks_no_working_session_jargon():
    """The README says what is and where its evidence is, not which of the
    team's working sessions ("stop 57", "since stop 64") or tracker issues
    ("issue 16's targets") made it so: a user knows neither. Line breaks
    count as spaces (a wrapped "stop\\n69" is caught too)."""
    text = " ".join(README.read_text().split())
    assert re.findall(r"\b(?:stop|issue)[ -]\d+", text, flags=re.I) == []
