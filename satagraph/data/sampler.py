r"""A training sampler whose order is a function of (seed, epoch) only, and
which can start an epoch part-way: what exact resume needs."""
from __future__ import annotations

from typing import Iterator, Optional, Sequence, Tuple, Union

import torch
from torch.utils.data import Sampler

#: What the sampler yields: an index, or ``(epoch, index)`` (see
#: :class:`~satagraph.data.dataset.EpochSampler`).
Key = Union[int, Tuple[int, int]]


class ResumableSampler(Sampler):
    r"""Random training order drawn from a generator seeded by ``(seed,
    epoch)``: a permutation, or :obj:`num_samples` draws with replacement
    by :obj:`weights` (balanced sampling). The order of an epoch never
    depends on earlier epochs, on the global random state or on a restart.

    :meth:`resume` makes the next iteration of one epoch skip its first
    samples (the batches a run had trained on before it was stopped);
    :meth:`__len__` stays the full epoch, so that step counts and limits
    do not change.

    Args:
        num_samples (int): Samples per epoch.
        weights (sequence of float, optional): Sampling weights (with
            replacement); uniform permutation without.
        seed (int): Base seed.
        keys (bool): Yield ``(epoch, index)`` keys (per-epoch augmentation)
            instead of indices.
    """

    def __init__(self, num_samples: int, weights: Optional[Sequence[float]] = None,
                 seed: int = 0, keys: bool = False) -> None:
        self.num_samples, self.seed, self.keys = int(num_samples), int(seed), keys
        self.weights = (None if weights is None
                        else torch.as_tensor(weights, dtype=torch.double))
        self.epoch = 0
        self._skip: Tuple[int, int] = (-1, 0)

    def set_epoch(self, epoch: int) -> None:
        """The epoch of the next iteration (Lightning calls it every epoch)."""
        self.epoch = int(epoch)

    def resume(self, epoch: int, consumed: int) -> None:
        """Start at sample :obj:`consumed` of :obj:`epoch` (once)."""
        self.epoch = int(epoch)
        self._skip = (int(epoch), int(consumed))

    def order(self, epoch: int) -> torch.Tensor:
        """The indices of an epoch."""
        gen = torch.Generator().manual_seed((self.seed * 1_000_003 + epoch) % (2 ** 63))
        if self.weights is None:
            return torch.randperm(self.num_samples, generator=gen)
        return torch.multinomial(self.weights, self.num_samples, replacement=True,
                                 generator=gen)

    def __iter__(self) -> Iterator[Key]:
        epoch = self.epoch
        skip_epoch, skip = self._skip
        start = skip if skip_epoch == epoch else 0
        self._skip = (-1, 0)
        for i in self.order(epoch)[start:].tolist():
            yield (epoch, i) if self.keys else i

    def __len__(self) -> int:
        return self.num_samples


__all__ = ["ResumableSampler"]
