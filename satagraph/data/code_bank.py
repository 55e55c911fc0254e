r"""A bank of frozen RVQ codes for text-to-motion training.

A generator step spends most of its time in the frozen autoencoder: on two
CPU cores, encoding a batch of 16 windows of 120 frames takes 1.9 s of a
2.4 s step, the two transformers 0.15 s (``experiments/T2M.md`` section 20).
A :class:`CodeBank` stores what a step reads of a captioned window once:
its per-frame code stacks, its skeleton graph (static and semantic joint
features normalised as the autoencoder's, parents), its caption and its
duration. Training on a bank (``data.code_bank``) skips the autoencoder and
the data pipeline; each window's augmentation (mirroring, bone scaling,
caption phrasing) is the one drawn when the bank was made.

A bank belongs to one autoencoder: it records the autoencoder's
:func:`autoencoder_fingerprint` (every weight but the decoder's, so a
decoder fine-tuned under frozen codes keeps its banks), which training
checks. Banks are written with ``satagraph code-bank`` as safetensors files
(tensors, and the captions as JSON metadata; no pickle).
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any, Iterable, List, NamedTuple, Optional, Sequence, Union

import torch
from torch import Tensor
from torch.utils.data import Dataset

from satagraph.nn.generators.skeleton_embedding import SkeletonGraph, skeleton_graph
from satagraph.nn.generators.skeleton_topology import parents_to_edge_index
from satagraph.nn.generators.codes import length_mask, split_codes

PathLike = Union[str, Path]
#: Format tag in a bank file's metadata.
FORMAT = "satagraph-code-bank/1"


class CodeBatch(NamedTuple):
    r"""A batch of banked windows: what a text-to-motion step reads.

    Shapes:
        - **codes**: :math:`(B, T_{max}, Q)` (``-1`` after each window),
          **num_frames**: :math:`(B,)`, **seconds**: :math:`(B,)`
        - **skeleton**: one graph per window (see
          :class:`~satagraph.nn.generators.SkeletonGraph`)
    """
    codes: Tensor
    num_frames: Tensor
    texts: List[str]
    skeleton: SkeletonGraph
    seconds: Tensor

    def to(self, device: Any) -> "CodeBatch":
        """The batch on :obj:`device`."""
        graph = SkeletonGraph(*(t.to(device) for t in self.skeleton))
        return CodeBatch(self.codes.to(device), self.num_frames.to(device), self.texts,
                         graph, self.seconds.to(device))

    def __len__(self) -> int:
        return len(self.texts)


def autoencoder_fingerprint(autoencoder: torch.nn.Module) -> str:
    """SHA-256 of every weight and buffer of :obj:`autoencoder` but its
    decoder's (what its codes and normalised features depend on)."""
    digest = hashlib.sha256()
    for key, value in sorted(autoencoder.state_dict().items()):
        if ".decoder." in f".{key}":
            continue
        digest.update(key.encode())
        digest.update(value.detach().float().cpu().contiguous().numpy().tobytes())
    return digest.hexdigest()


def _offsets(counts: Tensor) -> Tensor:
    return torch.cat([counts.new_zeros(1), counts.cumsum(0)])


class CodeBank(Dataset):
    r"""Banked windows; an item is its own index, :meth:`collate` gathers
    a :class:`CodeBatch`.

    Args:
        codes (Tensor): Code stacks of all windows, window after window.
        num_frames (Tensor): Frames per window.
        x (Tensor): Skeleton node features of all windows.
        parent (Tensor): Parent of every node within its window (``-1``:
            root).
        num_nodes (Tensor): Nodes per window.
        seconds (Tensor): Duration of every window.
        texts (list of str): Caption of every window.
        fingerprint (str): :func:`autoencoder_fingerprint` of the
            autoencoder that made the codes.

    Shapes:
        - **codes**: :math:`(G, Q)`, **num_frames**: :math:`(N,)`
        - **x**: :math:`(S, F)`, **parent**: :math:`(S,)`,
          **num_nodes**: :math:`(N,)`, **seconds**: :math:`(N,)`
    """

    def __init__(self, codes: Tensor, num_frames: Tensor, x: Tensor, parent: Tensor,
                 num_nodes: Tensor, seconds: Tensor, texts: Sequence[str],
                 fingerprint: str) -> None:
        count = len(texts)
        if not (num_frames.numel() == num_nodes.numel() == seconds.numel() == count):
            raise ValueError(f"a bank of {count} captions has {num_frames.numel()} frame "
                             f"counts, {num_nodes.numel()} node counts and "
                             f"{seconds.numel()} durations")
        if int(num_frames.sum()) != codes.size(0) or int(num_nodes.sum()) != x.size(0):
            raise ValueError("the bank's counts do not add up to its codes or nodes")
        self.codes, self.num_frames = codes, num_frames.long()
        self.x, self.parent, self.num_nodes = x, parent.long(), num_nodes.long()
        self.seconds, self.texts, self.fingerprint = seconds.float(), list(texts), fingerprint
        self._frame_start = _offsets(self.num_frames)
        self._node_start = _offsets(self.num_nodes)

    def __len__(self) -> int:
        return len(self.texts)

    def __getitem__(self, index: int) -> int:
        if not -len(self) <= index < len(self):
            raise IndexError(f"window {index} of a bank of {len(self)}")
        return index % len(self)

    def collate(self, indices: Sequence[int]) -> CodeBatch:
        """The :class:`CodeBatch` of windows :obj:`indices` (a loader's
        ``collate_fn``)."""
        index = torch.as_tensor(list(indices), dtype=torch.long)
        frames, nodes = self.num_frames[index], self.num_nodes[index]
        codes = torch.cat([self.codes[self._frame_start[i]:self._frame_start[i + 1]]
                           for i in index.tolist()]).long()
        x = torch.cat([self.x[self._node_start[i]:self._node_start[i + 1]]
                       for i in index.tolist()]).float()
        local = torch.cat([self.parent[self._node_start[i]:self._node_start[i + 1]]
                           for i in index.tolist()])
        clip = torch.arange(len(index)).repeat_interleave(nodes)
        parent = torch.where(local < 0, -1, local + _offsets(nodes)[:-1][clip])
        edge_index, root = parents_to_edge_index(parent)
        return CodeBatch(split_codes(codes, frames), frames, [self.texts[i] for i in index],
                         SkeletonGraph(x, edge_index, clip, root), self.seconds[index])

    # ------------------------------------------------------------ files
    def save(self, path: PathLike) -> None:
        """Write the bank as one safetensors file (atomically)."""
        from safetensors.torch import save_file

        from satagraph.utils.files import atomic_path
        tensors = {"codes": self.codes.to(torch.int16).contiguous(),
                   "num_frames": self.num_frames, "x": self.x.half().contiguous(),
                   "parent": self.parent.to(torch.int32), "num_nodes": self.num_nodes,
                   "seconds": self.seconds}
        meta = {"format": FORMAT, "fingerprint": self.fingerprint,
                "texts": json.dumps(self.texts)}
        with atomic_path(path, create_parent=True) as tmp:
            save_file(tensors, tmp, metadata=meta)

    @classmethod
    def load(cls, path: PathLike) -> "CodeBank":
        """Read a bank written by :meth:`save`.

        Raises:
            ValueError: :obj:`path` is not a code bank (one line naming it).
        """
        from safetensors import SafetensorError, safe_open
        try:
            with safe_open(str(path), framework="pt") as f:
                meta = f.metadata() or {}
                if meta.get("format") != FORMAT:
                    raise ValueError(f"{path}: not a satagraph code bank "
                                     f"(format {meta.get('format')!r})")
                tensors = {k: f.get_tensor(k) for k in f.keys()}
        except (OSError, RuntimeError, SafetensorError) as err:
            raise ValueError(f"{path}: cannot read the code bank ({err})") from None
        try:
            return cls(tensors["codes"], tensors["num_frames"], tensors["x"], tensors["parent"],
                       tensors["num_nodes"], tensors["seconds"], json.loads(meta["texts"]),
                       meta["fingerprint"])
        except (KeyError, ValueError) as err:
            raise ValueError(f"{path}: a damaged code bank ({err})") from None

    def check_autoencoder(self, autoencoder: torch.nn.Module, where: str = "code bank") -> None:
        """Refuses an autoencoder other than the one that made the codes."""
        if autoencoder_fingerprint(autoencoder) != self.fingerprint:
            raise ValueError(f"{where}: its codes are of another autoencoder than the "
                             "generator's (model.autoencoder); make it anew with "
                             "`satagraph code-bank`")


def bank_batch(module: Any, batch: Any) -> CodeBank:
    r"""The windows of one :class:`~satagraph.data.FrameBatch` as a bank,
    coded by ``module``'s frozen autoencoder
    (:meth:`~satagraph.lightning.TextToMotionModule.batch_codes`)."""
    from satagraph.data.captioned import batch_seconds, batch_texts
    codes, frames = module.batch_codes(batch)
    graph = skeleton_graph(module.autoencoder.normalize_batch(batch))
    nodes = torch.bincount(graph.batch, minlength=len(frames))
    parent = torch.full((graph.x.size(0),), -1, dtype=torch.long)
    parent[graph.edge_index[1]] = graph.edge_index[0]
    start = _offsets(nodes)[:-1][graph.batch]
    local = torch.where(parent < 0, -1, parent - start)
    real = codes[length_mask(frames, codes.size(1))]
    return CodeBank(real.cpu(), frames.cpu(), graph.x.detach().cpu(), local.cpu(), nodes.cpu(),
                    batch_seconds(batch), batch_texts(batch),
                    autoencoder_fingerprint(module.autoencoder))


def concat_banks(banks: Iterable[CodeBank]) -> CodeBank:
    """One bank of several of the same autoencoder."""
    banks = list(banks)
    if not banks:
        raise ValueError("no banks to join")
    if len({b.fingerprint for b in banks}) > 1:
        raise ValueError("banks of different autoencoders cannot be joined")
    cat = lambda name: torch.cat([getattr(b, name) for b in banks])  # noqa: E731
    return CodeBank(cat("codes"), cat("num_frames"), cat("x"), cat("parent"), cat("num_nodes"),
                    cat("seconds"), [t for b in banks for t in b.texts], banks[0].fingerprint)


def draw_code_bank(module: Any, loader_for_epoch: Any, windows: int,
                   progress: Optional[Any] = None) -> CodeBank:
    r"""At least :obj:`windows` training windows banked: batches of
    ``loader_for_epoch(epoch)`` for epochs 0, 1, ... (each epoch of the
    endless zoo draws new rigs and clips) coded by ``module``'s frozen
    autoencoder.

    Args:
        module: A :class:`~satagraph.lightning.TextToMotionModule`.
        loader_for_epoch (callable): Epoch -> iterable of
            :class:`~satagraph.data.FrameBatch`.
        windows (int): Windows wanted.
        progress (callable, optional): Called with the count so far.
    """
    parts, count, epoch = [], 0, 0
    with torch.no_grad():
        while count < windows:
            before = count
            for batch in loader_for_epoch(epoch):
                parts.append(bank_batch(module, batch))
                count += len(parts[-1])
                if progress is not None:
                    progress(count)
                if count >= windows:
                    break
            if count == before:
                raise ValueError("the training loader gave no windows")
            epoch += 1
    return concat_banks(parts)


__all__ = ["CodeBank", "CodeBatch", "autoencoder_fingerprint", "bank_batch", "concat_banks",
           "draw_code_bank"]
