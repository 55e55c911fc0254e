"""Property-based fuzzing of preprocessing on generated rigs (hypothesis,
seeded): every file either gives finite features or is refused with one
line naming it; nothing else escapes."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from satagraph.data.dataset import DEFAULT_PREPROCESSING, preprocess_file  # noqa: E402
from satagraph.data.validate import MotionValidationError  # noqa: E402
from satagraph.io import write_bvh  # noqa: E402
from satagraph.motion import Motion  # noqa: E402
from satagraph.ops.rotation import euler_to_matrix  # noqa: E402
from satagraph.skeleton import Skeleton  # noqa: E402

ROT = ("Zrotation", "Xrotation", "Yrotation")
POS = ("Xposition", "Yposition", "Zposition")


@st.composite
def rigs(draw) -> Motion:
    """A random rig (2-12 joints, bones of mixed lengths, sometimes
    degenerate or absurd) with a random motion (2-40 frames)."""
    num = draw(st.integers(2, 12))
    parents = [-1] + [draw(st.integers(0, j - 1)) for j in range(1, num)]
    scale = draw(st.sampled_from([1e-3, 1.0, 100.0]))
    kind = draw(st.sampled_from(["normal"] * 6 + ["zero", "absurd", "teleport"]))
    gen = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    offsets = gen.normal(0, 10, (num, 3)) * scale
    offsets[0] = 0
    if kind == "zero":
        offsets[:] = 0
    elif kind == "absurd":
        offsets[num - 1] *= 1e12
    frames = draw(st.integers(2, 40))
    rot = euler_to_matrix(__import__("torch").from_numpy(
        gen.uniform(-0.5, 0.5, (frames, num, 3))), "ZXY").numpy()
    trans = np.broadcast_to(offsets, (frames, num, 3)).copy()
    trans[:, 0] += np.cumsum(gen.normal(0, 0.5 * scale, (frames, 3)), axis=0)
    if kind == "teleport":
        trans[frames // 2, 0, 0] = 1e25
    skel = Skeleton([f"j{i}" for i in range(num)], np.array(parents), offsets,
                    [POS + ROT] + [ROT] * (num - 1))
    fps = draw(st.sampled_from([0.2, 24.0, 30.0, 60.0, 2000.0]))
    return Motion(skel, rot, trans, fps=fps)


@settings(max_examples=25, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(motion=rigs())
def test_preprocessing_gives_finite_features_or_a_named_error(motion: Motion,
                                                              tmp_path: Path) -> None:
    path = tmp_path / "rig.bvh"
    write_bvh(motion, path)
    try:
        feats = preprocess_file(str(path), DEFAULT_PREPROCESSING)
    except MotionValidationError as err:
        assert str(err).startswith(f"{path}: ") and "\n" not in str(err)
        return
    for name in ("q", "x", "x_rel", "v_q", "v_x", "r", "static"):
        assert np.isfinite(getattr(feats, name)).all(), name
    assert feats.height > 0
