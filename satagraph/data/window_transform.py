r"""Transforms of one's own on the training windows (``data.train_transform``).

A window transform takes a :class:`~satagraph.data.clip.MotionClip` (one
training window, after the built-in augmentation of ``data.augment``) and
returns one of the same skeleton and length, as PyG's ``transform`` does
for a :class:`~torch_geometric.data.Data`: noise on the features, a
dropped joint's semantics, a flag in ``meta``. It runs in the loader's
workers, before collation; validation and test windows are left as they
are. A config names a registered one::

    from satagraph.data.window_transform import register_window_transform

    def jitter(clip):              # a module-level function: workers pickle it
        clip.root = clip.root + 0.01 * torch.randn_like(clip.root)
        return clip

    register_window_transform("jitter", jitter)
    # satagraph train tiny data.train_transform=jitter (SATAGRAPH_PLUGINS
    # naming the file), or MotionDataModule(..., train_transform=jitter)
"""
from __future__ import annotations

from typing import Callable, Dict, List, Optional, Union

from satagraph.data.clip import MotionClip
from satagraph.utils.registry import register_name

WindowTransform = Callable[[MotionClip], MotionClip]
_TRANSFORMS: Dict[str, WindowTransform] = {}


def register_window_transform(name: str, transform: WindowTransform) -> None:
    """Make :obj:`transform` the one ``data.train_transform=name`` names.

    Args:
        name (str): The name a config gives.
        transform (callable): :class:`~satagraph.data.MotionClip` ->
            :class:`~satagraph.data.MotionClip`, run on every training window.

    Raises:
        ValueError: The name is taken or empty.
    """
    key = str(name).strip()
    if not key:
        raise ValueError(f"window transform {name!r}: an empty name; pick another")
    register_name(_TRANSFORMS, key, transform, "window transform")


def window_transform(spec: Union[None, str, WindowTransform]) -> Optional[WindowTransform]:
    """The transform :obj:`spec` names (``None``: none; a callable: itself).

    Raises:
        ValueError: A name nobody registered (one line: the registered ones,
            and how to add one).
    """
    if spec is None or callable(spec):
        return spec
    if spec not in _TRANSFORMS:
        known = ", ".join(sorted(_TRANSFORMS)) or "none"
        raise ValueError(f"data.train_transform {spec!r} is not registered (registered: "
                         f"{known}): register_window_transform(name, function) adds one, in "
                         "a file SATAGRAPH_PLUGINS names for the command line")
    return _TRANSFORMS[spec]


class TransformedCollate:
    r"""A collate function that transforms each window first; picklable
    (workers started by ``spawn`` receive it) where its parts are.

    Args:
        collate (callable): The collate function of the windows.
        transform (callable): A window transform.
    """

    def __init__(self, collate: Callable, transform: WindowTransform) -> None:
        self.collate, self.transform = collate, transform

    def __call__(self, clips: List[MotionClip]):
        return self.collate([self.transform(clip) for clip in clips])


__all__ = ["WindowTransform", "register_window_transform", "window_transform",
           "TransformedCollate"]
