"""What other BVH readers need of the files satagraph writes (Blender's
importer, bvhio), and what other exporters write that satagraph reads;
``benchmarks/interop.py`` checks the same against Blender itself."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from satagraph.io import BVHError, read_bvh, write_bvh
from satagraph.io.bvh_reader import written_by_satagraph
from satagraph.motion import Motion, RigSettings


def _frame_lines(text: str) -> list:
    """The lines after ``Frame Time:`` as Blender's importer takes them:
    every non-blank line to the end of the file is a frame."""
    lines = [line.split() for line in text.splitlines() if line.split()]
    start = next(i for i, line in enumerate(lines) if line[:2] == ["Frame", "Time:"])
    return lines[start + 1:]


def test_a_declared_file_has_nothing_after_its_frames(tiny_motion: Motion,
                                                      tmp_path: Path) -> None:
    """The declaration of a retargeted or canonical file is on the
    ``HIERARCHY`` line: after the frames, Blender's importer read it as a
    frame and failed (``could not convert string to float: '#'``)."""
    out = tmp_path / "out.bvh"
    write_bvh(tiny_motion.with_(rig=RigSettings("-Z", 0.01, declared=True)), out)
    text = out.read_text()
    assert text.splitlines()[0] == "HIERARCHY # satagraph: up_axis=-Z scale=0.01"
    frames = _frame_lines(text)
    assert len(frames) == tiny_motion.num_frames
    width = tiny_motion.skeleton.num_channels
    assert all(len(line) == width and np.isfinite(np.array(line, dtype=float)).all()
               for line in frames)
    again = read_bvh(out)
    assert again.rig == RigSettings("-Z", 0.01, declared=True) and written_by_satagraph(str(out))
    np.testing.assert_allclose(again.global_positions(), tiny_motion.global_positions(),
                               atol=1e-5)


@pytest.mark.parametrize("rig, says", [
    (RigSettings("+Y", 1.0, declared=True), "canonical up_axis=+Y scale=1"),
    (RigSettings("+Y", 0.01, declared=True), "up_axis=+Y scale=0.01"),
    (RigSettings("+Z", 1.0, declared=True), "up_axis=+Z scale=1"),
    (RigSettings("+Y", None, declared=True), "up_axis=+Y"),
    (RigSettings("+Y", 1.0), None)])
def test_the_declaration_says_canonical_for_y_up_metres_only(tiny_motion: Motion, tmp_path: Path,
                                                            rig: RigSettings, says) -> None:
    out = tmp_path / "out.bvh"
    write_bvh(tiny_motion.with_(rig=rig), out)
    first = out.read_text().splitlines()[0]
    assert first == ("HIERARCHY" if says is None else f"HIERARCHY # satagraph: {says}")


def test_a_file_of_an_earlier_version_keeps_its_trailing_declaration(
        tiny_motion: Motion, tmp_path: Path) -> None:
    """Files written before the declaration moved to the ``HIERARCHY``
    line still declare how they are read; a file without one declares
    nothing."""
    out = tmp_path / "old.bvh"
    write_bvh(tiny_motion, out)
    assert read_bvh(out).rig is None and not written_by_satagraph(str(out))
    out.write_text(out.read_text() + "# satagraph: canonical up_axis=+Y scale=1\n")
    assert read_bvh(out).rig == RigSettings("+Y", 1.0, declared=True)
    assert written_by_satagraph(str(out))


#: Another exporter's file: tabs and CRLF, ``Xrotation Yrotation Zrotation``
#: on every joint, 6 channels on a joint below the root, a leaf without an
#: End Site, a named End Site, a short frame time, blank lines at the end.
DIALECT = ["HIERARCHY", "ROOT Hips", "{", "\tOFFSET 0 0 0",
           "\tCHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation",
           "\tJOINT Spine", "\t{", "\t\tOFFSET 0 10 0",
           "\t\tCHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation",
           "\t\tJOINT Head", "\t\t{", "\t\t\tOFFSET 0 5 0",
           "\t\t\tCHANNELS 3 Xrotation Yrotation Zrotation",
           "\t\t\tEnd Site Head_end", "\t\t\t{", "\t\t\t\tOFFSET 0 3 0", "\t\t\t}", "\t\t}",
           "\t}", "\tJOINT Leg", "\t{", "\t\tOFFSET 2 -8 0",
           "\t\tCHANNELS 3 Xrotation Yrotation Zrotation", "\t}", "}", "MOTION",
           "Frames: 2", "Frame Time: 0.0333333",
           "1 2 3 0 0 0\t0 10 0 0 0 0\t0 0 0\t0 0 0",
           "0 0 0 0 0 90\t0 12 0 0 0 0\t90 0 0\t0 0 0", "", "", ""]


def test_another_exporters_dialect_reads_as_blender_reads_it(tmp_path: Path) -> None:
    """The file above reads with the positions Blender's importer gives
    (a named End Site was refused: ``unexpected 'Head_end'``); a keyword
    that only begins with ``Site`` is still an error."""
    path = tmp_path / "dialect.bvh"
    path.write_bytes("\r\n".join(DIALECT).encode())
    motion = read_bvh(path)
    assert motion.skeleton.names == ["Hips", "Spine", "Head", "Head_end", "Leg"]
    assert (motion.num_frames, motion.fps) == (2, 30.0)
    want = [[[1, 2, 3], [1, 12, 3], [1, 17, 3], [1, 20, 3], [3, -6, 3]],
            [[0, 0, 0], [-12, 0, 0], [-17, 0, 0], [-17, 0, 3], [8, 2, 0]]]
    np.testing.assert_allclose(motion.global_positions(), want, atol=1e-9)
    path.write_text("\n".join(DIALECT).replace("End Site Head_end", "End Sites"))
    with pytest.raises(BVHError, match=r"dialect\.bvh:14: expected 'End Site'"):
        read_bvh(path)
