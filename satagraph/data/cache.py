"""Processed-feature cache: one ``.npz`` per (file content, preprocessing
config), written atomically, loaded without pickle."""
from __future__ import annotations

import hashlib
import json
import warnings
from pathlib import Path
from typing import Dict, Optional

import numpy as np

from satagraph.data.features import MotionFeatures
from satagraph.motion import CanonicalTransform
from satagraph.skeleton import Skeleton
from satagraph.utils.cache import cache_root
from satagraph.utils.files import atomic_write, check_input_file

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
               height=np.array(feats.height))
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
    return MotionFeatures(skeleton=skel, fps=float(data["fps"]),
                          height=float(data["height"]), transform=transform,
                          **{k: data[k] for k in _ARRAYS})


def load_cached(cache_dir: Path, key: str) -> Optional[MotionFeatures]:
    """Cached features, or ``None`` (a corrupt entry is removed with a
    warning)."""
    path = Path(cache_dir) / f"{key}.npz"
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            return _unpack(data)
    except Exception as err:  # corrupt or from an incompatible version
        warnings.warn(f"ignoring unreadable cache entry {path}: {err}")
        path.unlink(missing_ok=True)
        return None


def store_cached(cache_dir: Path, key: str, feats: MotionFeatures) -> None:
    """Write an entry atomically (temp file + rename)."""
    cache_dir = Path(cache_dir)
    cache_dir.mkdir(parents=True, exist_ok=True)
    atomic_write(cache_dir / f"{key}.npz", lambda f: np.savez(f, **_pack(feats)),
                 binary=True, durable=False)
