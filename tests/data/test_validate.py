"""Checked data: bad files are found in every split at once, reported as one
error or skipped; the normaliser refuses absurd statistics."""
from __future__ import annotations

import csv
import re
from pathlib import Path
from typing import Dict, List

import numpy as np
import pytest

from satagraph.data.datamodule import MotionDataModule
from satagraph.data.dataset import MotionDatasetError
from satagraph.data.normalizer import FeatureNormalizer, NormalizerError
from satagraph.data.validate import MotionLimits, MotionValidationError, check_motion
from satagraph.datasets.zoo import write_zoo
from satagraph.io import read_bvh

#: name -> (split, edit of the lines of a good file, words of the error)
BAD = {
    "huge_root": ("train", "root", "implausible position"),
    "zero_offsets": ("val", "zero", "degenerate skeleton"),
    "fps_typed": ("test", "ft30", "not the frame rate"),
    "no_frames": ("train", "f0", "0 frame(s)"),
    "huge_offset": ("train", "offset", "implausible OFFSET"),
}


def _edit(lines: List[str], how: str) -> List[str]:
    out = list(lines)
    motion = out.index("MOTION")
    if how == "root":
        out[motion + 4] = " ".join(["1e30"] + out[motion + 4].split()[1:])
    elif how == "zero":
        out = [re.sub(r"OFFSET .*", "OFFSET 0 0 0", x) for x in out]
    elif how == "ft30":
        out[motion + 2] = "Frame Time: 30"
    elif how == "f0":
        out = out[:motion + 1] + ["Frames: 0", out[motion + 2]]
    elif how == "offset":
        k = [i for i, x in enumerate(out) if "OFFSET" in x][3]
        out[k] = "OFFSET 0 1e30 0"
    return out


@pytest.fixture(scope="module")
def poisoned_zoo(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small zoo (bipeds and quadrupeds) plus one bad file per kind of
    :data:`BAD`, spread over the three splits; returns the manifest."""
    out = tmp_path_factory.mktemp("zoo")
    rows = write_zoo(out, species=["biped", "quadruped"], clips=2, frames=40)
    lines = (out / rows[0]["path"]).read_text().splitlines()
    for name, (split, how, _) in BAD.items():
        (out / "biped" / f"{name}.bvh").write_text("\n".join(_edit(lines, how)) + "\n")
        rows.append(dict(rows[0], path=f"biped/{name}.bvh", split=split))
    with open(out / "manifest.tsv", "w", newline="") as f:
        writer = csv.DictWriter(f, list(rows[0]), delimiter="\t", lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    return out / "manifest.tsv"


def _dm(manifest: Path, cache: Path, **kwargs) -> MotionDataModule:
    return MotionDataModule(str(manifest), window=16, stride=16, batch_size=4,
                            cache_dir=str(cache), **kwargs)


def test_every_bad_file_of_every_split_in_one_error(poisoned_zoo: Path,
                                                    tmp_path: Path) -> None:
    with pytest.raises(MotionDatasetError) as info:
        _dm(poisoned_zoo, tmp_path).setup("fit")
    text = str(info.value)
    assert text.startswith(f"{len(BAD)} of ") and "data.on_error=skip" in text
    for name, (split, _, words) in BAD.items():
        line = next(x for x in text.splitlines() if f"{name}.bvh" in x)
        assert line.strip().startswith(f"{split}: ") and words in line, line


def test_on_error_skip_trains_on_the_rest(poisoned_zoo: Path, tmp_path: Path) -> None:
    dm = _dm(poisoned_zoo, tmp_path, on_error="skip")
    with pytest.warns(UserWarning, match=f"left out {len(BAD)} of"):
        dm.setup("fit")
    assert len(dm.skipped) == len(BAD)
    kept = [f.path for ds in dm.datasets.values() for f in ds.files]
    assert not any(name in p for name in BAD for p in kept)
    assert all(np.isfinite(v).all() for v, _ in dm.normalizer.stats().values())
    with pytest.raises(ValueError, match="on_error"):
        _dm(poisoned_zoo, tmp_path, on_error="ignore")


def test_check_motion_accepts_the_zoo(poisoned_zoo: Path) -> None:
    for path in sorted(poisoned_zoo.parent.glob("*/*.bvh")):
        if path.stem not in BAD:
            check_motion(read_bvh(path), fps=30.0)


def test_resampling_size_is_bounded(poisoned_zoo: Path) -> None:
    motion = read_bvh(next(poisoned_zoo.parent.glob("biped/*walk*.bvh")))
    slow = motion.with_(fps=1.0)  # 40 s at 1 fps
    limits = MotionLimits(max_joint_frames=40 * 30 * motion.num_joints)
    check_motion(slow, "slow.bvh", fps=30.0, limits=limits)
    with pytest.raises(MotionValidationError, match="joint-frames"):
        check_motion(slow, "slow.bvh", fps=31.0, limits=limits)
    with pytest.raises(MotionValidationError, match="s long"):
        check_motion(slow, "slow.bvh", limits=MotionLimits(max_duration=39))


class _Feats:
    def __init__(self, scale: float) -> None:
        gen = np.random.default_rng(0)
        from satagraph.data.features import DYNAMIC_CHANNELS, ROOT_CHANNELS, STATIC_CHANNELS
        self.dynamic = gen.normal(size=(8, 5, DYNAMIC_CHANNELS))
        self.r = gen.normal(size=(8, ROOT_CHANNELS))
        self.static = gen.normal(size=(5, STATIC_CHANNELS)) * scale
        self.height = 1.0


@pytest.mark.parametrize("scale", [1e30, np.nan])
def test_normaliser_refuses_absurd_statistics(scale: float) -> None:
    feats: Dict[str, _Feats] = {"good.bvh": _Feats(1.0), "bad.bvh": _Feats(scale)}
    with pytest.raises(NormalizerError, match="most extreme file is bad.bvh"):
        FeatureNormalizer().fit(list(feats.values()), list(feats))
    FeatureNormalizer().fit([feats["good.bvh"]])
