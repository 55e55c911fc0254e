"""Many sources onto one target from Python
(:class:`~satagraph.pipelines.inference.Retargeter`): the target's work done
once, each output written to the byte as :func:`retarget_motion` writes it,
wrong inputs refused in one line before any work."""
from __future__ import annotations

import copy
from collections import Counter
from functools import partial
from pathlib import Path
from typing import Callable, List

import numpy as np
import pytest

from satagraph.datasets.zoo import generate_clip, zoo_rigs
from satagraph.experiment.train import load_module
from satagraph.io import write_bvh
from satagraph.motion import Motion
from satagraph.pipelines import inference
from satagraph.pipelines.inference import Retargeter, RigMemo, retarget_motion


@pytest.fixture(scope="module")
def model():
    return load_module("builtin")


@pytest.fixture(scope="module")
def walks() -> List[Motion]:
    biped = zoo_rigs(["biped"])[0]
    return [generate_clip(biped, "walk", frames=24, seed=1),
            generate_clip(biped, "run", frames=30, seed=2)]


@pytest.fixture(scope="module")
def dog() -> Motion:
    return generate_clip(zoo_rigs(["quadruped"])[0], "walk", frames=20, seed=3)


def written(motion: Motion, path: Path) -> bytes:
    write_bvh(motion, str(path))
    return path.read_bytes()


def test_the_pipeline_api_exports_it() -> None:
    from satagraph import pipelines
    assert pipelines.Retargeter is Retargeter and pipelines.RigMemo is RigMemo
    assert pipelines.retarget_motion is retarget_motion
    assert {"Retargeter", "retarget_motion"} <= set(pipelines.__all__)


def test_zoo_clips_come_out_as_retarget_motion_writes_them_the_target_read_once(
        model, walks: List[Motion], dog: Motion, tmp_path: Path, monkeypatch) -> None:
    alone = [written(retarget_motion(model, walk, dog, plant=True), tmp_path / f"a{i}.bvh")
             for i, walk in enumerate(walks)]
    seen, canonicalize = [], inference.canonicalize
    monkeypatch.setattr(inference, "canonicalize",
                        lambda m, **kw: seen.append(m) or canonicalize(m, **kw))
    onto_dog = Retargeter(model, dog, plant=True)
    outs = onto_dog(walks) + [onto_dog(walks[0])]
    assert sum(m is dog for m in seen) == 1 and len(seen) == 4
    assert [written(out, tmp_path / f"b{i}.bvh") for i, out in enumerate(outs)] == (
        alone + alone[:1])


def test_a_generator_of_sources_and_the_target_s_work_done_once(
        model, walks: List[Motion], dog: Motion, tmp_path: Path, monkeypatch) -> None:
    """A generator (clips streamed from disk) was refused (``source:
    expected a satagraph Motion, got generator``); the target was checked,
    and its ground level and semantic embedding computed, at every clip."""
    alone = [written(retarget_motion(model, walk, dog, model.embed), tmp_path / f"a{i}.bvh")
             for i, walk in enumerate(walks)]
    calls: Counter = Counter()
    for name in ("check_target", "ground_level", "mean_carriage", "_embed"):
        monkeypatch.setattr(inference, name, partial(
            lambda name, run, *args: calls.update([name]) or run(*args), name,
            getattr(inference, name)))
    onto_dog = Retargeter(model, dog, model.embed)
    outs = onto_dog(walk for walk in walks + walks)
    assert calls == {"check_target": 1, "ground_level": 1, "mean_carriage": 1,
                     "_embed": 1 + 4}  # + each source
    assert [written(out, tmp_path / f"b{i}.bvh") for i, out in enumerate(outs)] == alone * 2


@pytest.mark.parametrize("source, target", [
    ("bandai/dataset-1_dash_normal_001.bvh", "dog/D1_010_KAN01_002.bvh"),
    ("cmu/depressed_18_000.bvh", "ccbase/006_01.bvh")])
def test_real_clips_come_out_as_retarget_motion_writes_them(
        model, read_real: Callable[[str], Motion], source: str, target: str,
        tmp_path: Path) -> None:
    src, tgt = read_real(source), read_real(target)
    expected = written(retarget_motion(model, src, tgt, model.embed), tmp_path / "alone.bvh")
    onto = Retargeter(model, tgt, model.embed)
    assert [written(out, tmp_path / f"{i}.bvh") for i, out in enumerate(onto([src, src]))] == (
        [expected, expected])


def one_line_error(error: pytest.ExceptionInfo) -> str:
    message = str(error.value)
    assert "\n" not in message
    return message


def test_wrong_inputs_are_refused_in_one_line_before_any_retarget(
        model, walks: List[Motion], dog: Motion, monkeypatch) -> None:
    from satagraph.data.validate import MotionValidationError
    with pytest.raises(TypeError) as error:
        Retargeter(model, "dog.bvh")
    assert one_line_error(error) == ("target: expected a satagraph Motion, got str; read it "
                                     "first: satagraph.io.read_bvh('dog.bvh')")
    with pytest.raises(TypeError, match="module: expected a loaded model, got 'builtin'"):
        Retargeter("builtin", dog)
    with pytest.raises(ValueError, match="rest must be one of"):
        Retargeter(model, dog, rest="tpose")
    with pytest.raises(ValueError, match="windows of 8 frames sharing 8"):
        Retargeter(model, dog, window=8, overlap=8)
    onto_dog = Retargeter(model, dog)
    with pytest.raises(TypeError, match="source: expected a satagraph Motion, got str"):
        onto_dog("walk.bvh")
    monkeypatch.setattr(inference, "retarget_canonical", lambda *a, **kw: pytest.fail("ran"))
    with pytest.raises(TypeError) as error:
        onto_dog([walks[0], "walk.bvh"])
    assert one_line_error(error).startswith("sources[1]: expected a satagraph Motion, got str")
    short = walks[1].slice(0, 1)
    with pytest.raises(MotionValidationError) as error:
        onto_dog([walks[0], short])
    assert one_line_error(error) == f"{short.source}: 1 frame(s): at least 2 are needed"
    with pytest.raises(MotionValidationError, match=r"^sources\[1\]: 1 frame"):
        onto_dog([walks[0], short.with_(source=None)])


def test_a_folder_run_of_the_command_line_keeps_one_retargeter_per_model(model, dog) -> None:
    """``satagraph retarget SRC_DIR`` goes through the same class: one per
    model (``--ckpt auto`` may choose two), all keeping the target's work
    in one memo."""
    from satagraph.cli import build_parser, parse_args
    from satagraph.cli.train import _retargeter
    args = parse_args(build_parser(), ["retarget", "in", "--target", "dog.bvh", "out",
                                       "--plant"])
    memos: dict = {}
    first = _retargeter(args, model, model.embed, dog, memos)
    assert _retargeter(args, model, model.embed, dog, memos) is first
    other = _retargeter(args, copy.copy(model), None, dog, memos)  # another model
    assert other is not first and other.memo is first.memo is memos["target"]
    assert first.options["plant"] and first.target is dog
    assert _retargeter(args, model, model.embed, dog).memo is not first.memo


def test_the_carriage_is_passed_through_and_a_reconstruction_never_carried(
        model, walks: List[Motion], dog: Motion, tmp_path: Path) -> None:
    """``Retargeter(carriage=...)`` and ``retarget --carriage`` retarget as
    :func:`retarget_motion` does with that setting (``always`` turns every
    joint's mean to the quadruped clip's own, ``never`` keeps the
    decoder's); a reconstruction (the target the source itself) is never
    carried."""
    from satagraph.cli import build_parser, parse_args
    from satagraph.cli.train import _retargeter
    from satagraph.pipelines.inference import retarget_canonical
    walk = walks[0]
    got = {mode: written(Retargeter(model, dog, carriage=mode)(walk), tmp_path / f"{mode}.bvh")
           for mode in ("never", "always")}
    assert got["never"] != got["always"]
    for mode, expected in got.items():
        assert written(retarget_motion(model, walk, dog, carriage=mode),
                       tmp_path / f"alone_{mode}.bvh") == expected
        args = parse_args(build_parser(), ["retarget", "in", "--target", "dog.bvh", "out",
                                           "--carriage", mode])
        assert _retargeter(args, model, None, dog).options["carriage"] == mode
    kept, carried = (retarget_canonical(model, walk, walk, carriage=mode)[1]
                     for mode in ("never", "always"))
    np.testing.assert_array_equal(carried.rotations, kept.rotations)
    np.testing.assert_array_equal(carried.translations, kept.translations)


@pytest.mark.parametrize("landing, grounds", [(1.0, 1), (0.0, 2)])
def test_the_gate_reads_the_retarget_grounded_and_a_kept_one_is_that_reading(
        model, walks: List[Motion], dog: Motion, monkeypatch, landing: float,
        grounds: int) -> None:
    """``carriage="auto"`` reads ``lands`` of the retarget as it is
    grounded; where it keeps it (lands 1.0), that grounded reading is the
    output, not grounded again; where it carries it (lands 0.0), the
    carried motion is grounded once more. With ``ground=False`` the gate
    still reads it as grounded at the target's level (the output is not)."""
    seen, calls = [], Counter()
    monkeypatch.setattr(inference, "lands_against",
                        lambda motion, own: seen.append(motion) or landing)
    ground_retarget = inference.ground_retarget
    monkeypatch.setattr(inference, "ground_retarget",
                        lambda *args: calls.update(["ground"]) or ground_retarget(*args))
    _, out = inference.retarget_canonical(model, walks[0], dog, model.embed)
    assert len(seen) == 1 and calls["ground"] == grounds
    assert (seen[0] is out) == (grounds == 1)
    read, seen[:] = [], []  # ground=False: the output not grounded, the gate's reading is
    monkeypatch.setattr(inference, "ground_retarget",
                        lambda *args: read.append(args) or ground_retarget(*args))
    _, kept = inference.retarget_canonical(model, walks[0], dog, model.embed, ground=False)
    (_, _, target, level), = read
    assert level == inference.ground_level(target) and seen[0] is not kept
