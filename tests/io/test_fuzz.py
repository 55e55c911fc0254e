"""Property-based fuzzing of the BVH reader and writer (hypothesis, seeded:
``derandomize=True``): every generated file round-trips, every mutated
file reads or raises a :class:`BVHError` naming the file."""
from __future__ import annotations

from pathlib import Path
from typing import List, Tuple

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from satagraph.io import BVHError, read_bvh, write_bvh  # noqa: E402
from satagraph.motion import Motion  # noqa: E402
from satagraph.ops.rotation import euler_to_matrix  # noqa: E402
from satagraph.skeleton import Skeleton  # noqa: E402

FAST = settings(max_examples=25, derandomize=True, deadline=None, database=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])
ORDERS = ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX")
POS = ("Xposition", "Yposition", "Zposition")
NAME = st.text(st.sampled_from("abcXYZ019-.:äé脚"), min_size=1, max_size=8)


@st.composite
def skeletons(draw, max_joints: int = 8, depth_first: bool = True) -> Skeleton:
    """A random tree in depth-first order (the order of a BVH file: each
    joint's parent is the previous joint or one of its ancestors), or with
    :obj:`depth_first` false in any order that lists a parent before its
    children (a joint inserted after its siblings' subtrees), names,
    offsets, channel layouts of every rotation order, end sites at some
    leaves."""
    num = draw(st.integers(1, max_joints))
    parents = [-1]
    for j in range(1, num):
        if not depth_first:
            parents.append(draw(st.integers(0, j - 1)))
            continue
        chain = [j - 1]
        while parents[chain[-1]] >= 0:
            chain.append(parents[chain[-1]])
        parents.append(draw(st.sampled_from(chain)))
    names = draw(st.lists(NAME, min_size=num, max_size=num, unique=True))
    offsets = draw(st.lists(st.tuples(*[st.floats(-50, 50, allow_nan=False)] * 3),
                            min_size=num, max_size=num))
    leaves = {j for j in range(num) if j not in parents}
    channels, end_site, ended = [], [], set()
    for j in range(num):
        order = draw(st.sampled_from(ORDERS))
        rot = tuple(f"{a}rotation" for a in order)
        end = (j in leaves and j > 0 and parents[j] not in ended
               and draw(st.booleans()))
        if end:  # named as the reader names end sites
            ended.add(parents[j])
            names[j] = f"{names[parents[j]]}_end"
        if end:
            layout: Tuple[str, ...] = ()
        elif j == 0:
            layout = POS + rot
        else:
            layout = draw(st.sampled_from([rot, POS + rot, rot + POS]))
        channels.append(layout)
        end_site.append(end)
    return Skeleton(names, np.array(parents), np.array(offsets), channels,
                    np.array(end_site))


@st.composite
def motions(draw, depth_first: bool = True) -> Motion:
    skel = draw(skeletons(depth_first=depth_first))
    frames = draw(st.integers(0, 4))
    num = skel.num_joints
    gen = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    rot = np.broadcast_to(np.eye(3), (frames, num, 3, 3)).copy()
    trans = np.broadcast_to(skel.offsets, (frames, num, 3)).copy()
    for j, order in enumerate(skel.rotation_orders):
        if order:
            angles = gen.uniform(-170, 170, (frames, 3))
            angles[:, 1] = gen.uniform(-80, 80, frames)
            import torch
            rot[:, j] = euler_to_matrix(torch.from_numpy(np.radians(angles)), order).numpy()
        if skel.has_position_channels[j]:
            trans[:, j] = gen.uniform(-100, 100, (frames, 3))
    fps = draw(st.sampled_from([24.0, 30.0, 60.0, 120.0]))
    return Motion(skel, rot, trans, fps=fps)


@FAST
@given(motion=motions())
def test_write_read_round_trip(motion: Motion, tmp_path: Path) -> None:
    path = tmp_path / "clip.bvh"
    write_bvh(motion, path)
    back = read_bvh(path)
    a, b = motion.skeleton, back.skeleton
    assert b.names == a.names
    np.testing.assert_array_equal(b.parents, a.parents)
    assert b.channels == a.channels
    np.testing.assert_allclose(b.offsets, a.offsets, atol=1e-5)
    assert back.num_frames == motion.num_frames
    np.testing.assert_allclose(back.global_positions(), motion.global_positions(),
                               atol=1e-3)


@FAST
@given(motion=motions(depth_first=False))
def test_any_parent_first_order_round_trips(motion: Motion, tmp_path: Path) -> None:
    """A skeleton whose joints list each parent first but not depth-first
    is written in the file's depth-first order with each joint's own
    channels (write_bvh once put each joint's columns in another joint's
    block): read back, every joint has its parent, offset and positions."""
    path = tmp_path / "clip.bvh"
    write_bvh(motion, path)
    back = read_bvh(path)
    a, b = motion.skeleton, back.skeleton
    assert sorted(b.names) == sorted(a.names)
    perm = np.array([a.names.index(n) for n in b.names])  # back's joint k is a's perm[k]
    np.testing.assert_array_equal(a.parents[perm[1:]], perm[b.parents[1:]])
    assert [a.channels[j] for j in perm] == b.channels
    np.testing.assert_allclose(b.offsets, a.offsets[perm], atol=1e-5)
    np.testing.assert_allclose(back.global_positions(), motion.global_positions()[:, perm],
                               atol=1e-3)


def _base(tmp_path: Path) -> bytes:
    gen = np.random.default_rng(0)
    names = ["Hips", "Spine", "Head", "Leg"]
    skel = Skeleton(names, np.array([-1, 0, 1, 0]), gen.uniform(-10, 10, (4, 3)),
                    [POS + ("Zrotation", "Xrotation", "Yrotation")] +
                    [("Zrotation", "Xrotation", "Yrotation")] * 3)
    motion = Motion(skel, np.broadcast_to(np.eye(3), (3, 4, 3, 3)).copy(),
                    np.broadcast_to(skel.offsets, (3, 4, 3)).copy(), fps=30.0)
    write_bvh(motion, tmp_path / "base.bvh")
    return (tmp_path / "base.bvh").read_bytes()


MUTATION = st.tuples(st.sampled_from(["delete", "insert", "replace", "truncate", "swap"]),
                     st.floats(0, 1), st.binary(min_size=1, max_size=6))


@FAST
@given(mutations=st.lists(MUTATION, min_size=1, max_size=4))
def test_mutated_files_read_or_raise_bvh_error(mutations: List, tmp_path: Path) -> None:
    data = bytearray(_base(tmp_path))
    for kind, where, chunk in mutations:
        at = int(where * len(data))
        if kind == "delete":
            del data[at:at + len(chunk)]
        elif kind == "insert":
            data[at:at] = chunk
        elif kind == "replace":
            data[at:at + len(chunk)] = chunk
        elif kind == "truncate":
            del data[at:]
        else:
            lines = bytes(data).split(b"\n")
            i = int(where * (len(lines) - 1))
            lines[i], lines[-1 - i] = lines[-1 - i], lines[i]
            data = bytearray(b"\n".join(lines))
    path = tmp_path / "mutant.bvh"
    path.write_bytes(bytes(data))
    try:
        motion = read_bvh(path)
    except BVHError as err:
        assert str(err).startswith(f"{path}:") and "\n" not in str(err)
        return
    assert np.isfinite(motion.raw_channels).all()
    assert np.isfinite(motion.skeleton.offsets).all()


@FAST
@given(lines=st.lists(st.text(st.sampled_from("HIERARCHYROOTJOINTMOTION{}Frames:Time 0.5-e\t"),
                              max_size=30), max_size=20))
def test_random_text_reads_or_raises_bvh_error(lines: List[str], tmp_path: Path) -> None:
    path = tmp_path / "random.bvh"
    path.write_text("\n".join(lines))
    try:
        read_bvh(path)
    except BVHError as err:
        assert str(err).startswith(f"{path}:")
