"""`satagraph generate --prompts FILE`: one motion per prompt and skeleton
into a folder, each the motion `--text` gives with seed SEED + i, listed
in prompts.tsv; a bad prompts file or output is one line."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from satagraph.cli import main
from satagraph.cli.generate import prompt_stem, read_prompts
from satagraph.datasets.zoo import write_zoo
from satagraph.io import read_bvh
from satagraph.io.weights import builtin_path


def test_read_prompts_skips_blanks_and_comments(tmp_path: Path) -> None:
    path = tmp_path / "p.txt"
    path.write_text("# a list\n a person walks forward \n\n#no\nan insect turns left\n")
    assert read_prompts(str(path)) == ["a person walks forward", "an insect turns left"]
    path.write_text("# only a comment\n\n")
    with pytest.raises(ValueError, match="p.txt: no prompts"):
        read_prompts(str(path))
    path.write_bytes(b"caf\xe9 walks\n")
    with pytest.raises(ValueError, match="p.txt: not UTF-8"):
        read_prompts(str(path))


def test_prompt_stems_are_numbered_file_names() -> None:
    assert prompt_stem(7, "A person walks, then RUNS!") == "007_a-person-walks-then-runs"
    assert prompt_stem(0, "???") == "000_prompt"
    assert len(prompt_stem(3, "walks " * 30)) <= 44


@pytest.mark.skipif(not builtin_path("text-to-motion").is_file(),
                    reason="no built-in text-to-motion weights ship in this checkout")
def test_every_prompt_is_the_motion_text_gives_with_its_seed(tmp_path: Path, capsys,
                                                             monkeypatch) -> None:
    """Each prompt's file is what ``--text`` gives with its seed; each
    skeleton is made the model's inputs once, not once per prompt."""
    from satagraph.pipelines import generate as G
    write_zoo(tmp_path / "zoo", species=["biped"], clips=1, frames=20, seed=4)
    rig = str(sorted((tmp_path / "zoo" / "biped").glob("*.bvh"))[0])
    prompts = tmp_path / "p.txt"
    prompts.write_text("a dog walks forward\na person runs forward\n")
    out = tmp_path / "out"
    made, rig_inputs = [], G.rig_inputs
    monkeypatch.setattr(G, "rig_inputs", lambda *a: made.append(a) or rig_inputs(*a))
    assert main(["generate", "--prompts", str(prompts), "--skeleton", rig, str(out),
                 "--seconds", "1.5", "--seed", "5"]) == 0
    assert len(made) == 1
    said = capsys.readouterr()
    assert "generated 2 motions of 2 of 2 prompts" in said.out
    # a note on how a prompt was read says which prompt it is
    assert "prompt 1 ('a dog walks forward'): the generator read" in said.err
    rows = (out / "prompts.tsv").read_text().splitlines()
    assert rows[0] == "path\tprompt\tskeleton\tseconds\tseed" and len(rows) == 3
    second = rows[2].split("\t")
    assert second[1:] == ["a person runs forward", rig, "1.50", "6"]
    assert main(["generate", "--text", "a person runs forward", "--skeleton", rig,
                 str(tmp_path / "one.bvh"), "--seconds", "1.5", "--seed", "6"]) == 0
    listed, alone = read_bvh(out / second[0]), read_bvh(tmp_path / "one.bvh")
    np.testing.assert_array_equal(listed.raw_channels, alone.raw_channels)


@pytest.mark.parametrize("case", ["bvh-name", "file", "empty"])
def test_prompts_refuse_what_cannot_be_done(tmp_path: Path, capsys, case: str) -> None:
    prompts = tmp_path / "p.txt"
    prompts.write_text("" if case == "empty" else "a person walks forward\n")
    out = tmp_path / ("out.bvh" if case == "bvh-name" else "out")
    if case == "file":
        out.write_text("x")
    assert main(["generate", "--prompts", str(prompts), "--skeleton", "missing.bvh",
                 str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and ("no prompts" if case == "empty" else "not a folder") in err


@pytest.mark.skipif(not builtin_path("text-to-motion").is_file(),
                    reason="no built-in text-to-motion weights ship in this checkout")
def test_an_interrupted_prompts_run_lists_what_it_wrote(tmp_path: Path, monkeypatch,
                                                        capsys) -> None:
    """Ctrl-C after the first prompt left no prompts.tsv (or an earlier
    run's, listing files of other prompts)."""
    import satagraph.pipelines.generate as generate
    write_zoo(tmp_path / "zoo", species=["biped"], clips=1, frames=20, seed=4)
    rig = str(sorted((tmp_path / "zoo" / "biped").glob("*.bvh"))[0])
    prompts = tmp_path / "p.txt"
    prompts.write_text("a person walks forward\na person runs forward\n")
    out = tmp_path / "out"
    out.mkdir()
    (out / "prompts.tsv").write_text("path\tprompt\tskeleton\tseconds\tseed\nold.bvh\told\n")
    real, calls = generate.generate_on, []

    def stopped_at_the_second(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*args, **kwargs)
    monkeypatch.setattr(generate, "generate_on", stopped_at_the_second)
    assert main(["generate", "--prompts", str(prompts), "--skeleton", rig, str(out),
                 "--seconds", "1.0"]) == 130
    rows = (out / "prompts.tsv").read_text().splitlines()
    assert len(rows) == 2 and rows[1].startswith("000_a-person-walks-forward.bvh\t")
    assert (out / rows[1].split("\t")[0]).is_file()
