r"""A data loader of motion clips, as PyG's ``DataLoader`` is of graphs."""
from __future__ import annotations

from typing import Any, Optional

from torch.utils.data import DataLoader, Dataset

from satagraph.data.collate import collate_clips


class ClipLoader(DataLoader):
    r"""A data loader that batches :class:`~satagraph.data.MotionClip`
    objects of any skeletons and lengths into one
    :class:`~satagraph.data.FrameBatch` of frame graphs
    (:func:`~satagraph.data.collate_clips`), as
    :class:`torch_geometric.loader.DataLoader` batches ``Data`` objects. A
    clip is not a ``Data`` object (it holds a whole take, which becomes
    one graph per frame), so PyG's loader refuses it ("DataLoader found
    invalid type").

    .. code-block:: python

        from satagraph.data import ClipLoader
        for batch in ClipLoader(dataset, batch_size=8, shuffle=True):
            out = model(batch)

    Args:
        dataset (Dataset): Clips (a :class:`~satagraph.data.MotionDataset`,
            a list of :class:`~satagraph.data.MotionClip`, ...).
        batch_size (int, optional): Clips per batch (:obj:`None`: each item
            of :obj:`dataset` is already a list of clips). (default: :obj:`1`)
        shuffle (bool): Draw the clips in a new order every epoch.
            (default: :obj:`False`)
        **kwargs: Other arguments of :class:`torch.utils.data.DataLoader`
            (``num_workers``, ``generator``, ``drop_last``, ...).

    Raises:
        TypeError: If a ``collate_fn`` is given: the loader's is
            :func:`~satagraph.data.collate_clips` (a loader of one's own
            batching is :class:`torch.utils.data.DataLoader`).
    """

    def __init__(self, dataset: Dataset, batch_size: Optional[int] = 1, shuffle: bool = False,
                 **kwargs: Any) -> None:
        if "collate_fn" in kwargs:
            raise TypeError("ClipLoader: collate_fn is collate_clips; for a batching of your "
                            "own, use torch.utils.data.DataLoader(..., collate_fn=...)")
        super().__init__(dataset, batch_size=batch_size, shuffle=shuffle,
                         collate_fn=collate_clips, **kwargs)


__all__ = ["ClipLoader"]
