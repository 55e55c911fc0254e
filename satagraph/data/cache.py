"""Processed-feature cache: one ``.npz`` per (file content, preprocessing
config), written atomically, loaded without pickle. Reading an entry marks
it used (its modification time), so that :func:`prune_cache` can remove the
entries no run has read for a while (``satagraph cache``)."""
from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Tuple

import numpy as np

from satagraph.data.features import MotionFeatures
from satagraph.motion import CanonicalTransform
from satagraph.skeleton import Skeleton
from satagraph.utils.cache import cache_root
from satagraph.utils.files import atomic_write, check_input_file, sweep_stale_temps

#: Bump when the feature definition changes: old cache entries are ignored.
#: 2: files are checked (satagraph.data.validate) before they are cached.
#: 4: the canonical facing is read from the left/right pairs nearest the root.
#: 5: a leading bind-pose frame is given frame 1's pose (transforms.bind_frame).
#: 6: a root that carries the hips along the floor is folded into them
#: (transforms.canonical.fold_root), as a motionless one was, and so is one
#: with helper chains beside the hips (Unreal's IK roots), set aside.
#: 7: a rig whose up axis is not +Y has its rest pose turned upright too
#: (every joint's local axes, not the root's alone).
#: 8: a body stands where its root holds its height above the legs nearest
#: it (transforms.ground.stands): the rest shown for a line rest.
#: 9: a file's rest that faces away from +Z is shown turned to face it
#: (transforms.rest.rest_facing_turn).
FEATURE_VERSION = 9

_ARRAYS = ("x_local", "x_global", "edge_attr", "q", "x", "x_rel", "v_q", "v_x",
           "r", "c", "facing_axis")


def default_cache_dir() -> Path:
    """The cache root (:func:`satagraph.utils.cache.cache_root`):
    ``$SATAGRAPH_CACHE`` or ``~/.cache/satagraph``."""
    return cache_root()


def feature_cache_dir(cache_dir: Optional[str] = None) -> Path:
    """The folder of the feature entries: ``processed/`` under
    :obj:`cache_dir` (a config's ``data.cache_dir``) or the cache root."""
    return Path(cache_dir or default_cache_dir()) / "processed"


def content_digest(path: str, chunk: int = 1 << 20) -> str:
    """SHA-1 of a file's bytes, read a chunk at a time; what is not a
    regular file (a FIFO would block, ``/dev/zero`` never end) is refused
    first (:func:`~satagraph.utils.files.check_input_file`)."""
    check_input_file(path, "BVH file")
    digest = hashlib.sha1()
    with open(path, "rb") as handle:
        while block := handle.read(chunk):
            digest.update(block)
    return digest.hexdigest()


def cache_key(path: str, config: Dict) -> str:
    """Key from the file's content (an edit that keeps the size and the
    modification time, as ``cp -p`` or ``rsync -t`` make, is another key)
    and the config, not from where the file lies: features depend on its
    bytes alone, so a folder moved, renamed or linked in twice is read from
    the entries it already has."""
    blob = json.dumps([content_digest(path), config, FEATURE_VERSION], sort_keys=True)
    return hashlib.sha1(blob.encode()).hexdigest()


#: The arrays of the helper chains a folded root set aside (canonical.fold_root).
_HELPER_ARRAYS = ("index", "parents", "offsets", "end_site", "rotation", "translation")


def _pack(feats: MotionFeatures) -> Dict[str, np.ndarray]:
    skel = feats.skeleton
    out = {k: getattr(feats, k) for k in _ARRAYS}
    out.update(names=np.array(skel.names), parents=skel.parents, offsets=skel.offsets,
               channels=np.array([" ".join(c) for c in skel.channels]),
               end_site=skel.end_site, fps=np.array(feats.fps),
               height=np.array(feats.height),
               rig_warnings=np.array([list(w) for w in feats.rig_warnings], dtype=str
                                     ).reshape(-1, 2))
    tf = feats.transform
    if tf is not None:
        out.update(tf_up_axis=np.array(tf.up_axis), tf_up_rotation=tf.up_rotation,
                   tf_yaw=np.array(tf.yaw), tf_translation=tf.translation,
                   tf_scale=np.array(tf.scale), tf_source_fps=np.array(tf.source_fps))
        if tf.removed_root:
            rr = tf.removed_root
            out.update(rr_name=np.array(rr["name"]),
                       rr_channels=np.array(" ".join(rr["channels"])),
                       rr_offset=rr["offset"], rr_rotation=rr["rotation"],
                       rr_translation=rr["translation"], rr_child_offset=rr["child_offset"],
                       rr_carries=np.array(rr["carries"]))
            if rr.get("helpers"):
                h = rr["helpers"]
                out.update({f"rr_h_{k}": np.asarray(h[k]) for k in _HELPER_ARRAYS},
                           rr_h_names=np.array(h["names"]),
                           rr_h_channels=np.array([" ".join(c) for c in h["channels"]]))
    return out


def _unpack(data) -> MotionFeatures:
    skel = Skeleton(names=[str(n) for n in data["names"]], parents=data["parents"],
                    offsets=data["offsets"],
                    channels=[tuple(str(c).split()) for c in data["channels"]],
                    end_site=data["end_site"])
    transform = None
    if "tf_up_axis" in data:
        removed = None
        if "rr_name" in data:
            removed = {"name": str(data["rr_name"]),
                       "channels": tuple(str(data["rr_channels"]).split()),
                       "offset": data["rr_offset"], "rotation": data["rr_rotation"],
                       "translation": data["rr_translation"],
                       "child_offset": data["rr_child_offset"],
                       "carries": bool(data["rr_carries"]), "helpers": None}
            if "rr_h_index" in data:
                removed["helpers"] = dict(
                    {k: data[f"rr_h_{k}"] for k in _HELPER_ARRAYS},
                    names=[str(n) for n in data["rr_h_names"]],
                    channels=[tuple(str(c).split()) for c in data["rr_h_channels"]])
        transform = CanonicalTransform(
            up_axis=str(data["tf_up_axis"]), up_rotation=data["tf_up_rotation"],
            yaw=float(data["tf_yaw"]), translation=data["tf_translation"],
            scale=float(data["tf_scale"]), source_fps=float(data["tf_source_fps"]),
            removed_root=removed)
    said = data["rig_warnings"] if "rig_warnings" in data else ()  # none before
    return MotionFeatures(skeleton=skel, fps=float(data["fps"]),
                          height=float(data["height"]), transform=transform,
                          rig_warnings=tuple((str(k), str(t)) for k, t in said),
                          **{k: data[k] for k in _ARRAYS})


def load_cached(cache_dir: Path, key: str) -> Optional[MotionFeatures]:
    """Cached features, or ``None`` (a corrupt entry is removed with a
    warning; one that ``satagraph cache --clear`` removed meanwhile is a
    miss, said nothing of)."""
    path = Path(cache_dir) / f"{key}.npz"
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            feats = _unpack(data)
    except FileNotFoundError:
        return None
    except Exception as err:  # corrupt or from an incompatible version
        warnings.warn(f"ignoring unreadable cache entry {path}: {err}")
        path.unlink(missing_ok=True)
        return None
    with contextlib.suppress(OSError):  # a read-only cache is read all the same
        os.utime(path)  # used now: what prune_cache keeps
    return feats


def store_cached(cache_dir: Path, key: str, feats: MotionFeatures) -> None:
    """Write an entry atomically (temp file + rename)."""
    cache_dir = Path(cache_dir)
    cache_dir.mkdir(parents=True, exist_ok=True)
    atomic_write(cache_dir / f"{key}.npz", lambda f: np.savez(f, **_pack(feats)),
                 binary=True, durable=False)


# ---------------------------------------------------------------- upkeep
#: A feature entry's file name: the key of :func:`cache_key` (nothing
#: else in a folder is counted or removed).
ENTRY = re.compile(r"^[0-9a-f]{40}\.npz$")


@dataclass
class CacheUsage:
    r"""What a feature cache folder holds.

    Args:
        folder (Path): The folder (:func:`feature_cache_dir`).
        entries (int): Feature entries.
        bytes (int): Their size on disk.
        oldest (float, optional): The earliest last use of an entry (seconds
            since the epoch), ``None`` without entries.
        newest (float, optional): The latest last use.
    """

    folder: Path
    entries: int = 0
    bytes: int = 0
    oldest: Optional[float] = None
    newest: Optional[float] = None


def _entries(folder: Path) -> List[Tuple[str, os.stat_result]]:
    """``(path, stat)`` of every feature entry of :obj:`folder`."""
    try:
        listed = list(os.scandir(folder))
    except FileNotFoundError:
        return []
    out = []
    for entry in listed:
        if ENTRY.match(entry.name):
            with contextlib.suppress(OSError):  # removed meanwhile
                out.append((entry.path, entry.stat(follow_symlinks=False)))
    return out


def cache_usage(folder: Path) -> CacheUsage:
    """The entries of a feature cache folder, their size and last uses."""
    stats = [st for _, st in _entries(folder)]
    used = [st.st_mtime for st in stats]
    return CacheUsage(Path(folder), len(stats), sum(st.st_size for st in stats),
                      min(used, default=None), max(used, default=None))


def prune_cache(folder: Path, unused_days: Optional[float] = None,
                now: Optional[float] = None) -> Tuple[int, int]:
    """Remove the entries of :obj:`folder` that no run has read or written
    for :obj:`unused_days` days (every entry when ``None``); a run that
    needs one again computes it again. Only feature entries (:data:`ENTRY`)
    and temporary files of writers that no longer run are removed.

    Returns:
        The entries removed and the bytes they took.
    """
    if unused_days is not None and unused_days < 0:
        raise ValueError(f"cache: days unused must be 0 or more, got {unused_days:g}")
    cutoff = None if unused_days is None else (now or time.time()) - 86400.0 * unused_days
    removed = freed = 0
    for path, st in _entries(folder):
        if cutoff is not None and st.st_mtime >= cutoff:
            continue
        with contextlib.suppress(FileNotFoundError):  # another prune's
            os.unlink(path)
            removed, freed = removed + 1, freed + st.st_size
    sweep_stale_temps(folder)
    return removed, freed

