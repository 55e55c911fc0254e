"""`satagraph retarget` and `reconstruct` over a folder of BVH files: the
model loaded once, outputs at the same relative paths, a bad file said in
one line while the others go on, and no output for it."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from satagraph.cli import main
from satagraph.cli.folders import failure_line
from satagraph.datasets.sources import bvh_files, scan_folder
from satagraph.datasets.zoo import write_zoo
from satagraph.io import read_bvh


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two zoo walks (one in a subfolder), a broken file, a dangling link,
    a text file."""
    zoo = tmp_path_factory.mktemp("zoo")
    write_zoo(zoo, species=["biped", "quadruped"], clips=1, frames=40, seed=2)
    src = tmp_path_factory.mktemp("src")
    (src / "deep").mkdir()
    biped = sorted((zoo / "biped").glob("*.bvh"))[0]
    quad = sorted((zoo / "quadruped").glob("*.bvh"))
    (src / "walk.bvh").write_bytes(biped.read_bytes())
    (src / "deep" / "Trot.BVH").write_bytes(quad[0].read_bytes())
    (src / "deep" / "broken.bvh").write_text("HIERARCHY\nROOT Hips\n{\n")
    (src / "notes.txt").write_text("not motion")
    (src / "deep" / "gone.bvh").symlink_to(src / "nowhere.bvh")
    (src / "target.bvh").write_bytes(quad[-1].read_bytes())
    return src


def test_bvh_files_are_found_below_the_folder_in_any_case(folder: Path) -> None:
    names = [p.relative_to(folder).as_posix() for p in bvh_files(folder)]
    assert names == ["deep/Trot.BVH", "deep/broken.bvh", "deep/gone.bvh", "target.bvh",
                     "walk.bvh"]  # a broken link too: the reader says what it is

def test_training_reads_a_folder_by_the_same_rule(tmp_path: Path) -> None:
    """``scan_folder`` (training) found ``.bvh`` and ``.BVH`` only, leaving a
    ``.Bvh`` out unsaid while ``inspect`` listed it."""
    for name in ("a.bvh", "b.Bvh", "sub/c.BVH"):
        (tmp_path / name).parent.mkdir(exist_ok=True)
        (tmp_path / name).write_text("")
    assert [f.path for f in scan_folder(tmp_path)] == [str(p) for p in bvh_files(tmp_path)]
    assert len(bvh_files(tmp_path)) == 3


def test_retarget_a_folder_goes_on_past_a_bad_file(folder: Path, tmp_path: Path,
                                                   capsys) -> None:
    out = tmp_path / "out"
    target = folder / "target.bvh"
    code = main(["retarget", str(folder), "--target", str(target), str(out)])
    printed = capsys.readouterr()
    assert code == 2
    written = sorted(p.relative_to(out).as_posix() for p in bvh_files(out))
    assert written == ["deep/Trot.BVH", "target.bvh", "walk.bvh"]
    errors = [line for line in printed.err.splitlines() if "error" in line]
    assert len(errors) == 2 and "deep/broken.bvh:3:" in errors[0]
    assert "deep/gone.bvh" in errors[1] and "No such file" in errors[1]
    assert "retargeted 3 of 5 files" in printed.out and "2 failed" in printed.out
    assert printed.err.count("using the built-in model") == 1  # loaded once
    names = read_bvh(target).skeleton.names
    for path in bvh_files(out):
        motion = read_bvh(path)
        assert motion.skeleton.names == names and motion.num_frames == 40


def test_reconstruct_a_folder_keeps_each_rig(folder: Path, tmp_path: Path, capsys) -> None:
    good = tmp_path / "good"
    (good / "deep").mkdir(parents=True)
    for rel in ("walk.bvh", "deep/Trot.BVH"):
        (good / rel).write_bytes((folder / rel).read_bytes())
    out = good / "out"  # inside the input folder: never read as an input
    assert main(["reconstruct", str(good), str(out), "--no-mirror"]) == 0
    assert main(["reconstruct", str(good), str(out), "--no-mirror"]) == 0
    assert "reconstructed 2 of 2 files" in capsys.readouterr().out
    for rel in ("walk.bvh", "deep/Trot.BVH"):
        source, result = read_bvh(good / rel), read_bvh(out / rel)
        assert result.skeleton.names == source.skeleton.names
        assert result.num_frames == source.num_frames


@pytest.mark.slow  # four retargets by the built-in model: 11 s
def test_a_folder_retarget_writes_what_each_file_s_retarget_writes(
        folder: Path, tmp_path: Path, monkeypatch) -> None:
    """The target is canonicalised once for the folder (it was once per
    file), and every output is the file a retarget of that file alone
    writes, to the byte."""
    from satagraph.pipelines import inference
    good, target = tmp_path / "good", folder / "target.bvh"
    for sub in ("good/deep", "alone/deep"):
        (tmp_path / sub).mkdir(parents=True)
    for rel in ("walk.bvh", "deep/Trot.BVH"):
        (good / rel).write_bytes((folder / rel).read_bytes())
    for rel in ("walk.bvh", "deep/Trot.BVH"):
        assert main(["retarget", str(good / rel), "--target", str(target),
                     str(tmp_path / "alone" / rel)]) == 0
    seen, canonicalize = [], inference.canonicalize
    monkeypatch.setattr(inference, "canonicalize",
                        lambda m, **kw: seen.append(m.source) or canonicalize(m, **kw))
    assert main(["retarget", str(good), "--target", str(target), str(tmp_path / "out")]) == 0
    assert seen.count(str(target)) == 1 and len(seen) == 3
    for rel in ("walk.bvh", "deep/Trot.BVH"):
        assert (tmp_path / "out" / rel).read_bytes() == (tmp_path / "alone" / rel).read_bytes()


def test_skip_existing_goes_on_with_a_stopped_folder_run(folder: Path, tmp_path: Path,
                                                        capsys) -> None:
    """A folder run stopped with one result whole, one write killed (its
    temporary file left) and one cut short by a copy: ``--skip-existing``
    leaves out the whole one only (the same file, not rewritten) and counts
    it; a single file is skipped the same way."""
    from satagraph.io.bvh_reader import written_by_satagraph
    from satagraph.utils.files import HOST, is_temp_file
    good, out, target = tmp_path / "good", tmp_path / "out", folder / "target.bvh"
    (good / "deep").mkdir(parents=True)
    for rel in ("walk.bvh", "deep/Trot.BVH", "target.bvh"):
        (good / rel).write_bytes((folder / rel).read_bytes())
    assert main(["retarget", str(good), "--target", str(target), str(out)]) == 0
    killed = out / "deep" / f".Trot.BVH.{HOST}-999999999.0123abcd.tmp.BVH"
    (out / "deep" / "Trot.BVH").rename(killed)
    cut = (out / "target.bvh").read_bytes()
    (out / "target.bvh").write_bytes(cut[: len(cut) // 2])
    kept = (out / "walk.bvh").stat().st_ino
    capsys.readouterr()

    assert main(["retarget", str(good), "--target", str(target), str(out),
                 "--skip-existing"]) == 0
    printed = capsys.readouterr().out
    assert "retargeted 2 of 3 files" in printed and "; 1 skipped" in printed
    assert f"wrote {out / 'walk.bvh'}" not in printed
    assert (out / "walk.bvh").stat().st_ino == kept
    for rel in ("deep/Trot.BVH", "target.bvh"):
        assert written_by_satagraph(str(out / rel)) and read_bvh(out / rel).num_frames == 40
    assert not [p for p in out.rglob("*") if is_temp_file(p.name)]  # swept

    assert main(["retarget", str(good / "walk.bvh"), "--target", str(target),
                 str(out / "walk.bvh"), "--skip-existing"]) == 0
    assert "skipped, already there" in capsys.readouterr().out
    assert (out / "walk.bvh").stat().st_ino == kept


def test_skip_existing_leaves_what_another_run_makes_to_it(tmp_path: Path, capsys) -> None:
    """Two ``--skip-existing`` runs into one folder each decided at their
    start what to leave out, so each made every file: now a file whose
    claim another live run holds (it is making it), or whose result that
    run wrote since this one began, is left out at its turn and counted, as
    it is at the end: b.bvh, whose run never wrote it (it failed), was
    counted as 'made by another run' too."""
    from satagraph.cli.folders import complete_output, run_over_folder
    from satagraph.utils.files import atomic_write_text, file_lock
    src, out = tmp_path / "in", tmp_path / "out"
    src.mkdir()
    out.mkdir()
    for name in ("a", "b", "c"):
        (src / f"{name}.bvh").write_text("x")
    made = []

    def result(path: Path) -> None:  # a whole result: declared, and it reads
        atomic_write_text(path, "HIERARCHY # satagraph: up_axis=+Y\nROOT Hips\n{\n"
                          "OFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n"
                          "End Site\n{\nOFFSET 0 1 0\n}\n}\nMOTION\nFrames: 1\n"
                          "Frame Time: 0.0333333\n0 0 0\n")

    def one(source: str, output: str) -> str:
        made.append(Path(source).name)
        result(Path(output))
        if Path(source).name == "a.bvh":  # meanwhile the other run finishes c.bvh
            result(out / "c.bvh")
        return f"wrote {output}"

    with file_lock(out / ".b.bvh.claim", timeout=0):  # the other run makes b.bvh
        assert run_over_folder(src, out, one, "made", skip_existing=True) == 0
    printed = capsys.readouterr().out.splitlines()
    assert made == ["a.bvh"] and complete_output(out / "c.bvh")
    assert f"{out / 'b.bvh'}: skipped, another run makes it or has made it " \
        "(--skip-existing)" in printed
    assert printed[-1].startswith("made 1 of 3 files into") and printed[-1].endswith(
        "; 1 made by another run, 1 left to another run, not whole at the end (it failed "
        "on them or is still making them) (--skip-existing)")
    assert sorted(p.name for p in out.iterdir()) == ["a.bvh", "c.bvh"]  # no claim left


def test_a_killed_run_s_claims_are_swept_by_any_later_run(tmp_path: Path, capsys) -> None:
    """A ``--skip-existing`` run killed (``kill -9``) while it made a file left
    ``.NAME.claim`` beside it, which a later run without the flag (or one
    that found that output whole) never removed; a live run's claim stays."""
    from satagraph.cli.folders import run_over_folder
    from satagraph.utils.files import file_lock
    src, out = tmp_path / "in", tmp_path / "out"
    (src / "deep").mkdir(parents=True)
    (out / "deep").mkdir(parents=True)
    for rel in ("a.bvh", "deep/b.bvh"):
        (src / rel).write_text("x")
    (out / ".a.bvh.claim").write_text("")  # a killed run's: no lock held
    (out / "deep" / ".b.bvh.claim").write_text("")

    def one(source: str, output: str) -> str:
        Path(output).write_text("made")
        return f"wrote {output}"

    with file_lock(out / ".live.bvh.claim", timeout=0):  # another run, live
        assert run_over_folder(src, out, one, "made") == 0
        assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")) == [
            ".live.bvh.claim", "a.bvh", "deep", "deep/b.bvh"]
    assert "made 2 of 2 files" in capsys.readouterr().out


def test_the_claim_sweep_removes_only_the_claims_of_its_own_outputs(tmp_path: Path,
                                                                   capsys) -> None:
    """The sweep of a killed run's claims removed every ``.*.claim`` in the
    output folder, a user's ``.notes.claim`` among them; it removes the
    claims of the outputs the run makes and nothing else."""
    from satagraph.cli.folders import run_over_folder
    src, out = tmp_path / "in", tmp_path / "out"
    src.mkdir()
    out.mkdir()
    (src / "a.bvh").write_text("x")
    (out / ".a.bvh.claim").write_text("")  # a killed run's
    (out / ".notes.claim").write_text("mine")  # the user's
    (out / ".b.bvh.claim").write_text("")  # of an output this run does not make

    def one(source: str, output: str) -> str:
        Path(output).write_text("made")
        return f"wrote {output}"

    assert run_over_folder(src, out, one, "made") == 0
    assert sorted(p.name for p in out.iterdir()) == [".b.bvh.claim", ".notes.claim", "a.bvh"]
    assert (out / ".notes.claim").read_text() == "mine"
    capsys.readouterr()


@pytest.mark.parametrize("case", ["file", "bvh-name", "empty"])
def test_folder_runs_refuse_what_cannot_be_a_folder_job(folder: Path, tmp_path: Path,
                                                        capsys, case: str) -> None:
    source, out = folder, tmp_path / "results"
    if case == "file":
        out.write_text("x")
    elif case == "bvh-name":
        out = tmp_path / "results.bvh"
    else:
        source = tmp_path / "empty"
        source.mkdir()
    assert main(["reconstruct", str(source), str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert ("no .bvh files" if case == "empty" else "not a folder") in err


@pytest.mark.parametrize("out", [".", ".."])
def test_a_folder_whose_files_are_all_below_the_output_says_so(folder: Path, tmp_path: Path,
                                                              capsys, out: str) -> None:
    """``satagraph reconstruct takes takes`` (or into a folder above it) was
    told that the folder held no .bvh files."""
    source = tmp_path / "takes"
    source.mkdir()
    (source / "a.bvh").write_bytes((folder / "target.bvh").read_bytes())
    assert main(["reconstruct", str(source), str(source / out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert f"its 1 .bvh file(s) are all below the output folder {source / out}" in err
    assert sorted(p.name for p in source.iterdir()) == ["a.bvh"]


@pytest.mark.parametrize("command", ["retarget", "reconstruct"])
def test_a_missing_ckpt_is_refused_once_before_the_folder_is_made(
        folder: Path, tmp_path: Path, capsys, command: str) -> None:
    """``--ckpt MISSING`` over a folder was said once per file, into a new
    output folder left behind empty."""
    out = tmp_path / "new"
    target = ["--target", str(folder / "target.bvh")] if command == "retarget" else []
    assert main([command, str(folder), *target, str(out), "--ckpt", "none.ckpt"]) == 2
    assert capsys.readouterr().err == ("satagraph: error: none.ckpt: cannot read checkpoint "
                                       "or weights file: No such file or directory\n")
    assert not out.exists()


@pytest.mark.parametrize("command", ["retarget", "reconstruct"])
def test_a_source_without_a_skeleton_is_refused_before_a_model_is_chosen(
        folder: Path, tmp_path: Path, capsys, monkeypatch, command: str) -> None:
    """A one-joint source was given a model first (``--ckpt auto``: "using
    the built-in model builtin-wide (no limbs)", seconds of loading), then
    refused."""
    import satagraph.experiment.train as experiment

    def no_model(*args, **kwargs):
        raise AssertionError("a model was loaded for a file that is refused")

    monkeypatch.setattr(experiment, "load_module", no_model)
    one = tmp_path / "one.bvh"
    one.write_text("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition "
                   "Zposition\n}\nMOTION\nFrames: 2\nFrame Time: 0.033\n0 0 0\n1 1 1\n")
    target = ["--target", str(folder / "target.bvh")] if command == "retarget" else []
    assert main([command, str(one), *target, str(tmp_path / "out.bvh")]) == 2
    assert capsys.readouterr().err == (f"satagraph: error: {one}: a skeleton needs at least "
                                       "two joints\n")
    assert not (tmp_path / "out.bvh").exists()


def test_the_summary_names_ten_failures_at_most(tmp_path: Path, capsys) -> None:
    from satagraph.cli.folders import run_over_folder

    for i in range(12):
        (tmp_path / "in" / f"{i:02d}.bvh").parent.mkdir(exist_ok=True)
        (tmp_path / "in" / f"{i:02d}.bvh").write_text("x")

    def refuse(source: str, output: str) -> str:
        raise ValueError(f"{source}:1: bad")

    assert run_over_folder(tmp_path / "in", tmp_path / "out", refuse, "read") == 2
    printed = capsys.readouterr()
    assert printed.err.count("satagraph: error: ") == 12
    assert "0 of 12 files" in printed.out and "09.bvh and 2 more (each said above)" in printed.out
    assert "10.bvh" not in printed.out and not list((tmp_path / "out").rglob("*.bvh"))


def test_failure_line_names_the_file_once() -> None:
    assert failure_line("a.bvh", ValueError("a.bvh:3: bad")) == "a.bvh:3: bad"
    assert failure_line("a.bvh", RuntimeError("shape\nmismatch")) == "a.bvh: shape mismatch"
    assert failure_line("a.bvh", FileNotFoundError(2, "No such file", "a.bvh")) == \
        "a.bvh: No such file"


def test_inspect_a_folder_tabulates_every_file_and_sums_up(folder: Path, capsys) -> None:
    assert main(["inspect", str(folder)]) == 2
    printed = capsys.readouterr()
    lines = printed.out.splitlines()
    assert lines[0].split()[:3] == ["file", "joints", "frames"]
    rows = {line.split()[0]: line.split() for line in lines[1:-1]}
    assert set(rows) == {"deep/Trot.BVH", "target.bvh", "walk.bvh"}
    assert rows["walk.bvh"][1] == str(read_bvh(folder / "walk.bvh").num_joints)
    assert rows["walk.bvh"][2] == "40" and rows["walk.bvh"][5] == "+Y"
    assert lines[-1] == ("5 files: up axis +Y 3; units m 3; 0 with warnings; "
                         "0 with a bind pose as frame 0; 2 unreadable")
    errors = printed.err.splitlines()
    assert len(errors) == 2 and "broken.bvh:3:" in errors[0] and "gone.bvh" in errors[1]
    assert main(["inspect", str(folder), "--json"]) == 2
    infos = json.loads(capsys.readouterr().out)
    assert sorted(Path(i["file"]).name for i in infos) == ["Trot.BVH", "target.bvh", "walk.bvh"]


def test_inspect_a_folder_whose_every_file_is_unreadable(tmp_path: Path, capsys) -> None:
    """A table of no rows was a ``TypeError`` traceback (``max`` of one
    number); a folder holding only half a file (a killed copy) is common."""
    (tmp_path / "half.bvh").write_text("HIERARCHY\nROOT Hips\n{\n")
    assert main(["inspect", str(tmp_path)]) == 2
    printed = capsys.readouterr()
    assert printed.out.splitlines()[0].split()[:3] == ["file", "joints", "frames"]
    assert printed.out.splitlines()[-1].startswith("1 files:")
    assert printed.out.rstrip().endswith("1 unreadable")
    assert printed.err.splitlines() == [printed.err.splitlines()[0]]
    assert "half.bvh:3:" in printed.err and "Traceback" not in printed.err


def test_inspect_a_folder_reads_its_manifest_s_rig_settings(tmp_path: Path, capsys) -> None:
    """A folder whose ``manifest.tsv`` gives each file's ``up_axis`` and
    ``scale`` (as ``satagraph zoo`` writes it, and as training reads them):
    ``inspect`` guessed instead (bipeds 28 units tall read as humans in CMU
    units, 1.5 m, where the manifest says 1.66-1.87 m)."""
    from satagraph.datasets.zoo.dialects import Dialect
    write_zoo(tmp_path, species=["biped"], clips=1, frames=8,
              dialects=[Dialect(up_axis="+Z", unit=28.0)])
    (folder,) = {p.parent for p in tmp_path.rglob("*.bvh")}
    truth = {Path(f.path).name: f.scale for f in scan_folder(tmp_path)}
    assert main(["inspect", str(folder), "--json"]) == 0
    infos = json.loads(capsys.readouterr().out)
    assert len(infos) == len(truth) == 4
    for info in infos:
        rig = info["rig"]
        assert (rig["up_axis"], rig["up_axis_how"], rig["units_how"]) == ("+Z", "given", "given")
        assert rig["scale"] == pytest.approx(truth[Path(info["file"]).name])


def test_inspect_a_folder_s_flags_win_over_its_manifest(tmp_path: Path, capsys) -> None:
    """``--up-axis`` and ``--units`` given to ``inspect FOLDER`` are read over
    the manifest's columns, as for one file (the manifest's won, so a user
    checking another reading of a folder saw the manifest's again)."""
    from satagraph.datasets.zoo.dialects import Dialect
    write_zoo(tmp_path, species=["biped"], clips=1, frames=8,
              dialects=[Dialect(up_axis="+Z", unit=28.0)])
    (folder,) = {p.parent for p in tmp_path.rglob("*.bvh")}
    assert main(["inspect", str(folder), "--json", "--up-axis", "+Y", "--units", "0.5"]) == 0
    for info in json.loads(capsys.readouterr().out):
        assert (info["rig"]["up_axis"], info["rig"]["scale"]) == ("+Y", pytest.approx(0.5))
    assert main(["inspect", str(folder), "--json", "--units", "0.5"]) == 0
    for info in json.loads(capsys.readouterr().out):  # the manifest's axis where no flag
        assert (info["rig"]["up_axis"], info["rig"]["scale"]) == ("+Z", pytest.approx(0.5))


def test_an_interrupted_folder_run_says_how_far_it_went(tmp_path: Path, capsys) -> None:
    """A Ctrl-C in a folder run said only 'interrupted (outputs are written
    whole or not at all)', not how many files were done."""
    from satagraph.cli.folders import run_over_folder
    src = tmp_path / "in"
    src.mkdir()
    for i in range(5):
        (src / f"{i}.bvh").write_text("x")

    def one(source: str, output: str) -> str:
        if source.endswith("3.bvh"):
            raise KeyboardInterrupt
        Path(output).write_text("made")
        return f"wrote {output}"

    with pytest.raises(KeyboardInterrupt):
        run_over_folder(src, tmp_path / "out", one, "made")
    printed = capsys.readouterr()
    assert f"made 3 of 5 files into {tmp_path / 'out'} before the interrupt" in printed.err
    assert sorted(p.name for p in (tmp_path / "out").glob("*.bvh")) == ["0.bvh", "1.bvh", "2.bvh"]
