"""What a retarget computes of its target alone, kept across the sources
of a folder (:class:`~satagraph.pipelines.inference.RigMemo`): made once,
and the retargets the same as without it."""
from __future__ import annotations

from typing import Callable

import numpy as np
import pytest

from satagraph.motion import Motion
from satagraph.pipelines import inference
from satagraph.pipelines.inference import RigMemo, retarget_motion

DOG = "dog/D1_010_KAN01_002.bvh"                # 60 fps
BANDAI = "bandai/dataset-1_dash_normal_001.bvh"  # 30 fps, 20 frames
HUMAN = "cmu/depressed_18_000.bvh"              # 120 fps


def test_a_memo_makes_each_value_once_per_object_and_key() -> None:
    memo, made = RigMemo(), []

    def make(value: int) -> Callable[[], int]:
        return lambda: made.append(value) or value

    a, b = object(), object()
    assert memo(a, "k", make(1)) == 1 and memo(a, "k", make(2)) == 1
    assert memo(a, ("k", 30.0), make(3)) == 3 and memo(b, "k", make(4)) == 4
    assert made == [1, 3, 4]
    assert all(memo.kept[(id(of), key)][0] is of for of, key in ((a, "k"), (b, "k")))


@pytest.mark.parametrize("mirror, two_rests", [
    (False, False), pytest.param(True, True, marks=pytest.mark.slow)])
def test_retargets_with_one_memo_are_those_without(
        mirror: bool, two_rests: bool, build_tiny_module: Callable,
        read_real: Callable[[str], Motion], embed: Callable, monkeypatch) -> None:
    """A folder's sources onto one target: the target canonicalised once,
    not once per source, the outputs those of separate calls to the bit."""
    module = build_tiny_module("vae")
    target = read_real(HUMAN).slice(0, 90)
    sources = [read_real(BANDAI), read_real(DOG).slice(0, 40)]
    options = dict(window=16, overlap=4, mirror=mirror, two_rests=two_rests)
    alone = [retarget_motion(module, s, target, embed, **options) for s in sources]
    seen, canonicalize = [], inference.canonicalize
    monkeypatch.setattr(inference, "canonicalize",
                        lambda m, **kw: seen.append(m) or canonicalize(m, **kw))
    memo = RigMemo()
    kept = [retarget_motion(module, s, target, embed, memo=memo, **options) for s in sources]
    assert sum(m is target for m in seen) == 1 and len(seen) == 3
    for a, b in zip(alone, kept):
        assert np.array_equal(a.rotations, b.rotations)
        assert np.array_equal(a.translations, b.translations)
        assert np.array_equal(a.skeleton.offsets, b.skeleton.offsets)
