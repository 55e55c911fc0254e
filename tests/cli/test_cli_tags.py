"""``satagraph tags``: table, JSON, overrides, prompt export, answer import."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import pytest

from satagraph.cli.tags import add_tags_parser, main, run_tags

BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT LeftUpLeg
  {
    OFFSET 10 -5 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LeftLeg
    {
      OFFSET 0 -40 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 -40 0
      }
    }
  }
  JOINT Bone
  {
    OFFSET 0 0 -10
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT Bone.001
    {
      OFFSET 0 0 -10
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 0 -10
      }
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.033333
0 90 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0
0 90 1 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0
"""
NAMES = ["Hips", "LeftUpLeg", "LeftLeg", "LeftLeg_end", "Bone", "Bone.001",
         "Bone.001_end"]


@pytest.fixture
def bvh(tmp_path) -> Path:
    path = tmp_path / "tiny.bvh"
    path.write_text(BVH)
    return path


def run(capsys, *argv):
    """``satagraph tags`` on the tiny rig, whose still rest pose gives no up
    axis to be sure of: it is given (see test_uncertain_up_axis_is_said)."""
    code = main([str(a) for a in argv] + ["--up-axis=+Y"])
    out, err = capsys.readouterr()
    return code, out, err


def test_parser_registers_on_subparsers(bvh):
    parser = argparse.ArgumentParser(prog="satagraph")
    add_tags_parser(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["tags", str(bvh), "--anchor", "Bone=tail base",
                              "--anchor", "Bone.001=tail tip segment"])
    assert args.func is run_tags and args.anchor == [
        "Bone=tail base", "Bone.001=tail tip segment"]


def test_uncertain_up_axis_is_said_and_names_decide(bvh, capsys):
    code = main([str(bvh)])
    out, err = capsys.readouterr()
    assert code == 0 and err.startswith("satagraph: note: ")
    assert "the up axis is uncertain" in err and "names only" in err
    assert out == run(capsys, bvh, "--names-only")[1]


def test_table(bvh, capsys):
    code, out, err = run(capsys, bvh)
    assert code == 0 and err == ""
    lines = out.splitlines()
    assert lines[0].split() == ["#", "joint", "parent", "description"]
    assert len(lines) == 1 + len(NAMES)
    assert "left hind limb upper segment" in lines[2]
    assert lines[2].split()[:3] == ["1", "LeftUpLeg", "Hips"]


def test_json_with_dictionary_and_anchors(bvh, tmp_path, capsys):
    dictionary = tmp_path / "d.json"
    dictionary.write_text(json.dumps({"Hips": "center of mass"}))
    code, out, _ = run(capsys, bvh, "--json", "--dictionary", dictionary,
                       "--anchor", "Bone=tail base")
    assert code == 0
    rows = json.loads(out)
    assert [r["name"] for r in rows] == NAMES
    by = {r["name"]: r for r in rows}
    assert by["Hips"]["description"] == "center of mass"
    assert by["Hips"]["parent"] is None and by["LeftLeg"]["parent"] == \
        "LeftUpLeg"
    assert by["Bone"]["description"] == "tail base"
    assert by["Bone.001"]["description"] == \
        "tail base, first segment down the chain"
    assert by["Bone.001_end"]["description"] == "tail base tip"


def test_prompt_to_file_and_alignment_mode(bvh, tmp_path, capsys):
    out_file = tmp_path / "prompt.txt"
    code, out, _ = run(capsys, bvh, "--prompt", "--out", out_file)
    assert code == 0 and out == ""
    text = out_file.read_text()
    assert "# Mode: GENERATION" in text and "Bone.001 [Bone]" in text
    vocab = tmp_path / "vocab.json"
    vocab.write_text(json.dumps(["tail segment", "pelvis"]))
    code, out, _ = run(capsys, bvh, "--prompt", "--reference-vocab", vocab)
    assert code == 0 and "# Mode: ALIGNMENT" in out and '"pelvis"' in out


def test_import_answer(bvh, tmp_path, capsys):
    answer = tmp_path / "answer.json"
    answer.write_text(json.dumps({n: f"desc of {n}" for n in NAMES}))
    out_file = tmp_path / "dict.json"
    code, out, _ = run(capsys, bvh, "--import", answer, "--out", out_file)
    assert code == 0 and "7" in out
    assert json.loads(out_file.read_text())["Bone"] == "desc of Bone"
    code, out, _ = run(capsys, bvh, "--json", "--dictionary", out_file)
    assert json.loads(out)[4]["description"] == "desc of Bone"


@pytest.mark.parametrize("extra,needle", [
    (["--anchor", "Nope=x"], "no joint"),
    (["--anchor", "bad"], "NAME=TAG"),
    (["--import", "ANSWER"], "--out"),
    (["--import", "ANSWER", "--out", "OUT"], "missing"),
    (["--reference-vocab", "VOCAB"], "--prompt"),
    (["--prompt", "--reference-vocab", "VOCAB"], "not found"),
    (["--dictionary", "BADDICT"], "not valid JSON"),
])
def test_errors_are_one_line_exit_2(bvh, tmp_path, capsys, extra, needle):
    answer = tmp_path / "answer.json"
    answer.write_text(json.dumps({"Hips": "x"}))
    bad = tmp_path / "bad.json"
    bad.write_text("{oops")
    subst = {"ANSWER": answer, "OUT": tmp_path / "o.json",
             "VOCAB": tmp_path / "none.json", "BADDICT": bad}
    code, out, err = run(capsys, bvh, *[subst.get(a, a) for a in extra])
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("satagraph: error:")
    assert needle in err


def test_missing_bvh_exit_2(tmp_path, capsys):
    code, _, err = run(capsys, tmp_path / "none.bvh")
    assert code == 2 and "none.bvh" in err and err.count("\n") == 1


def test_refused_command_leaves_no_output_folder(bvh, tmp_path, capsys):
    """``--out NEW/x.txt`` with a missing input is refused and leaves no
    empty ``NEW`` behind (the output check made it before the input was
    read); a command that writes makes it."""
    code, _, err = run(capsys, tmp_path / "none.bvh", "--out", tmp_path / "new" / "x.txt")
    assert code == 2 and "none.bvh" in err
    assert not (tmp_path / "new").exists()
    assert run(capsys, bvh, "--out", tmp_path / "new" / "deeper" / "x.txt")[0] == 0
    assert (tmp_path / "new" / "deeper" / "x.txt").read_text().split()[:2] == ["#", "joint"]


@pytest.mark.parametrize("where", ["folder", "under a file"])
def test_unwritable_out_said_as_convert_says_it(bvh, tmp_path, capsys, where):
    """``--out`` that cannot be written is one line in the words every
    command uses for its output (it was ``[Errno 21] Is a directory: '...'``,
    after the descriptions were computed), as ``convert`` says it."""
    from satagraph.cli import main as satagraph
    target = tmp_path / "out" if where == "folder" else tmp_path / "file" / "x.txt"
    (tmp_path / "out").mkdir()
    (tmp_path / "file").write_text("not a folder")
    code, _, err = run(capsys, bvh, "--out", target)
    assert code == 2
    assert satagraph(["convert", str(bvh), str(target)]) == 2
    assert err.splitlines() == capsys.readouterr().err.splitlines()
    assert err.startswith(f"satagraph: error: cannot write {target}: ")


def test_output_spelled_as_demo_and_sweep_spell_it(bvh, tmp_path, capsys):
    """``--output`` (demo's and sweep's spelling) writes what ``--out``
    writes (it was ``unrecognized arguments: --output``)."""
    short, long = tmp_path / "out.txt", tmp_path / "output.txt"
    assert run(capsys, bvh, "--out", short)[0] == 0
    assert run(capsys, bvh, "--output", long)[0] == 0
    assert long.read_text() == short.read_text() != ""
