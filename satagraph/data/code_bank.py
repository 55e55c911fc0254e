r"""A bank of frozen RVQ codes for text-to-motion training.

A generator step spends most of its time in the frozen autoencoder: on two
CPU cores, encoding a batch of 16 windows of 120 frames takes 1.9 s of a
2.4 s step, the two transformers 0.15 s (``experiments/T2M.md`` section 20).
A :class:`CodeBank` stores what a step reads of a captioned window once:
its per-frame code stacks, its skeleton graph (static and semantic joint
features normalised as the autoencoder's, parents), its caption and the
duration of its captioned motion (and whether that is only a lower bound,
see :class:`~satagraph.nn.generators.LengthModel`). Training on a bank (``data.code_bank``) skips the autoencoder and
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
import re
import time
import warnings
from pathlib import Path
from typing import Any, Dict, Iterable, List, NamedTuple, Optional, Sequence, Tuple, Union

import torch
from torch import Tensor
from torch.utils.data import Dataset

PathLike = Union[str, Path]
#: Format tag in a bank file's metadata.
FORMAT = "satagraph-code-bank/1"


class CodeBatch(NamedTuple):
    r"""A batch of banked windows: what a text-to-motion step reads (the
    model turns the parents into bones and splits the codes per window).

    Shapes:
        - **codes**: :math:`(G, Q)` code stacks, window after window,
          **num_frames**: :math:`(B,)`
        - **x**: :math:`(S, F)` skeleton node features, **parent**:
          :math:`(S,)` parent node (``-1``: a root), **node_clip**:
          :math:`(S,)` window of every node
        - **seconds**: :math:`(B,)` durations of the captioned motions,
          **censored**: :math:`(B,)` bool, which are only lower bounds
    """
    codes: Tensor
    num_frames: Tensor
    x: Tensor
    parent: Tensor
    node_clip: Tensor
    texts: List[str]
    seconds: Tensor
    censored: Optional[Tensor] = None

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
        seconds (Tensor): Duration of every window's captioned motion
            (``meta["seconds"]`` of :mod:`~satagraph.data.captioned`).
        texts (list of str): Caption of every window.
        fingerprint (str): :func:`autoencoder_fingerprint` of the
            autoencoder that made the codes.
        censored (Tensor, optional): Which durations are only lower bounds
            (default: none; banks made before 29 Nov record none).

    Shapes:
        - **codes**: :math:`(G, Q)`, **num_frames**: :math:`(N,)`
        - **x**: :math:`(S, F)`, **parent**: :math:`(S,)`,
          **num_nodes**: :math:`(N,)`, **seconds**, **censored**: :math:`(N,)`
    """

    def __init__(self, codes: Tensor, num_frames: Tensor, x: Tensor, parent: Tensor,
                 num_nodes: Tensor, seconds: Tensor, texts: Sequence[str],
                 fingerprint: str, censored: Optional[Tensor] = None) -> None:
        count = len(texts)
        censored = torch.zeros(count, dtype=torch.bool) if censored is None else censored
        if not (num_frames.numel() == num_nodes.numel() == seconds.numel() == count
                == censored.numel()):
            raise ValueError(f"a bank of {count} captions has {num_frames.numel()} frame "
                             f"counts, {num_nodes.numel()} node counts, "
                             f"{seconds.numel()} durations and {censored.numel()} "
                             "censoring flags")
        if int(num_frames.sum()) != codes.size(0) or int(num_nodes.sum()) != x.size(0):
            raise ValueError("the bank's counts do not add up to its codes or nodes")
        self.codes, self.num_frames = codes, num_frames.long()
        self.x, self.parent, self.num_nodes = x, parent.long(), num_nodes.long()
        self.seconds, self.texts, self.fingerprint = seconds.float(), list(texts), fingerprint
        #: What the windows were drawn from (``{"sources": ..., "window": ...}``,
        #: set by ``satagraph code-bank``; ``None`` when not known).
        self.data: Optional[Dict[str, Any]] = None
        self.censored = censored.bool()
        self._frame_start = _offsets(self.num_frames)
        self._node_start = _offsets(self.num_nodes)

    def __len__(self) -> int:
        return len(self.texts)

    def __getitem__(self, index: int) -> int:
        if not -len(self) <= index < len(self):
            raise IndexError(f"window {index} of a bank of {len(self)}")
        return index % len(self)

    @classmethod
    def of_batch(cls, codes: Tensor, num_frames: Tensor, x: Tensor, parent: Tensor,
                 node_clip: Tensor, seconds: Tensor, texts: Sequence[str],
                 fingerprint: str, censored: Optional[Tensor] = None) -> "CodeBank":
        """A bank of one batch's windows, given as a :class:`CodeBatch`
        holds them (parents indexing the batch's nodes)."""
        nodes = torch.bincount(node_clip, minlength=num_frames.numel())
        start = _offsets(nodes)[:-1][node_clip]
        local = torch.where(parent < 0, -1, parent - start)
        return cls(codes.cpu(), num_frames.cpu(), x.detach().cpu(), local.cpu(), nodes.cpu(),
                   seconds.cpu(), texts, fingerprint,
                   None if censored is None else censored.cpu())

    def skeleton(self, index: int) -> Tuple[Tensor, Tensor]:
        """Window :obj:`index`'s node features and parents (within the
        window, ``-1``: the root), as banked."""
        nodes = slice(int(self._node_start[index]), int(self._node_start[index + 1]))
        return self.x[nodes], self.parent[nodes]

    def collate(self, indices: Sequence[int]) -> CodeBatch:
        """The :class:`CodeBatch` of windows :obj:`indices` (a loader's
        ``collate_fn``)."""
        index = torch.as_tensor(list(indices), dtype=torch.long)
        nodes = self.num_nodes[index]
        codes = torch.cat([self.codes[self._frame_start[i]:self._frame_start[i + 1]]
                           for i in index.tolist()]).long()
        x, local = (torch.cat(parts) for parts in
                    zip(*(self.skeleton(i) for i in index.tolist())))
        x = x.float()
        clip = torch.arange(len(index)).repeat_interleave(nodes)
        parent = torch.where(local < 0, -1, local + _offsets(nodes)[:-1][clip])
        return CodeBatch(codes, self.num_frames[index], x, parent, clip,
                         [self.texts[i] for i in index], self.seconds[index],
                         self.censored[index])

    # ------------------------------------------------------------ files
    def save(self, path: PathLike) -> None:
        """Write the bank as one safetensors file (atomically).

        Raises:
            OSError: It cannot be written (``No space left on device``),
                naming :obj:`path` (safetensors' own writer raises a
                ``SafetensorError`` that names neither).
        """
        from satagraph.io.weights import safetensors_bytes
        from satagraph.utils.files import atomic_write_bytes
        tensors = {"codes": self.codes.to(torch.int16).contiguous(),
                   "num_frames": self.num_frames, "x": self.x.half().contiguous(),
                   "parent": self.parent.to(torch.int32), "num_nodes": self.num_nodes,
                   "seconds": self.seconds, "censored": self.censored.to(torch.uint8)}
        meta = {"format": FORMAT, "fingerprint": self.fingerprint,
                "texts": json.dumps(self.texts)}
        if self.data is not None:
            meta["data"] = json.dumps(self.data)
        atomic_write_bytes(path, safetensors_bytes(tensors, meta), create_parent=True)

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
            bank = cls(tensors["codes"], tensors["num_frames"], tensors["x"], tensors["parent"],
                       tensors["num_nodes"], tensors["seconds"], json.loads(meta["texts"]),
                       meta["fingerprint"], tensors.get("censored"))
            bank.data = json.loads(meta["data"]) if "data" in meta else None
        except (KeyError, ValueError) as err:
            raise ValueError(f"{path}: a damaged code bank ({err})") from None
        return bank

    def check_data(self, sources: Any, window: int, where: str = "code bank") -> None:
        """Warn when the bank's windows were drawn from other sources or at
        another window length than a run names: it trains on the bank's
        windows, and records the run's."""
        if self.data is None:
            return
        if self.data.get("sources") != sources or self.data.get("window") != window:
            warnings.warn(f"{where}: its windows were drawn from {self.data.get('sources')} "
                          f"({self.data.get('window')} frames); this run names {sources} "
                          f"({window} frames), but trains on the bank's windows (draw it "
                          "anew with `satagraph code-bank --data ...` to train on yours)",
                          stacklevel=2)

    def check_autoencoder(self, autoencoder: torch.nn.Module, where: str = "code bank") -> None:
        """Refuses an autoencoder other than the one that made the codes."""
        if autoencoder_fingerprint(autoencoder) != self.fingerprint:
            raise ValueError(f"{where}: its codes are of another autoencoder than the "
                             "generator's (model.autoencoder); make it anew with "
                             "`satagraph code-bank`")


#: Fewest windows of one skeleton that make it a captured rig to
#: :func:`swap_skeletons` (the endless zoo draws a new rig for every window).
RIG_WINDOWS = 20


def skeleton_keys(bank: CodeBank, indices: Optional[Sequence[int]] = None) -> List[bytes]:
    """A key per window (of :obj:`indices`, default all) that is equal for
    windows of one skeleton (its parents and node features, as banked)."""
    indices = range(len(bank)) if indices is None else indices
    return [parent.numpy().tobytes() + x.half().numpy().tobytes()
            for x, parent in map(bank.skeleton, indices)]


#: Caption words that make a window a human's to :func:`swap_skeletons`.
HUMAN_WORDS = ("person", "someone")


def captured_rigs(bank: CodeBank, words: Sequence[str] = HUMAN_WORDS,
                  min_windows: int = RIG_WINDOWS) -> List[List[int]]:
    """The windows of each skeleton (:func:`skeleton_keys`) that has at
    least :obj:`min_windows` windows whose captions have one of
    :obj:`words`."""
    said = re.compile(r"\b(" + "|".join(map(re.escape, words)) + r")\b")
    spoken = [i for i, text in enumerate(bank.texts) if said.search(text)]
    windows: dict = {}
    for i, key in zip(spoken, skeleton_keys(bank, spoken)):
        windows.setdefault(key, []).append(i)
    return [w for w in windows.values() if len(w) >= min_windows]


def check_swap_share(share: float) -> float:
    """:obj:`share` if it is a probability, else a ``ValueError``."""
    if not 0.0 <= share <= 1.0:
        raise ValueError(f"the share of windows to swap (--swap-rigs) must be in [0, 1], "
                         f"got {share}")
    return share


def swap_skeletons(bank: CodeBank, share: float, words: Sequence[str] = HUMAN_WORDS,
                   seed: int = 0, min_windows: int = RIG_WINDOWS) -> CodeBank:
    r"""A bank in which windows of captured rigs of one kind are shown on
    each other's skeletons: each window whose caption has one of
    :obj:`words` and whose skeleton has at least :obj:`min_windows` windows
    (a captured rig: CMU's, CC_Base's; never a zoo rig) takes, with
    probability :obj:`share`, the skeleton of a window of another such rig,
    its codes and caption kept.

    SATA's codes are meant to be the same whatever the rig: codes generated
    for a CC_Base skeleton decode on CMU's rig as the motion asked
    (``experiments/T2M.md`` section 82). A generator shown each captured
    human rig with the others' motion learns what any of them can do; a rig
    with one captioned clip (CMU's) is otherwise tied to that clip's
    actions.
    """
    check_swap_share(share)
    rigs = captured_rigs(bank, words, min_windows)
    if len(rigs) < 2 or share == 0.0:
        return bank
    rng = torch.Generator().manual_seed(int(seed))
    donor = list(range(len(bank)))
    for r, members in enumerate(rigs):
        others = [w for k, rig in enumerate(rigs) if k != r for w in rig]
        for i in members:
            if float(torch.rand((), generator=rng)) < share:
                donor[i] = others[int(torch.randint(len(others), (), generator=rng))]
    x, parent = (torch.cat(parts) for parts in zip(*map(bank.skeleton, donor)))
    return CodeBank(bank.codes, bank.num_frames, x, parent, bank.num_nodes[donor],
                    bank.seconds, bank.texts, bank.fingerprint, bank.censored)


def concat_banks(banks: Iterable[CodeBank]) -> CodeBank:
    """One bank of several of the same autoencoder."""
    banks = list(banks)
    if not banks:
        raise ValueError("no banks to join")
    if len({b.fingerprint for b in banks}) > 1:
        raise ValueError("banks of different autoencoders cannot be joined")
    cat = lambda name: torch.cat([getattr(b, name) for b in banks])  # noqa: E731
    return CodeBank(cat("codes"), cat("num_frames"), cat("x"), cat("parent"), cat("num_nodes"),
                    cat("seconds"), [t for b in banks for t in b.texts], banks[0].fingerprint,
                    cat("censored"))


class DrawInterrupted(KeyboardInterrupt):
    """Ctrl-C while :func:`draw_code_bank` drew: :attr:`bank` holds the
    windows of the batches coded before it (the batch in hand is dropped),
    a whole bank as ``max_seconds`` gives; a :class:`KeyboardInterrupt`,
    so that code which does not keep them stops as before."""

    def __init__(self, bank: CodeBank) -> None:
        super().__init__(f"interrupted after {len(bank)} windows")
        self.bank = bank


def draw_code_bank(module: Any, loader_for_epoch: Any, windows: int,
                   progress: Optional[Any] = None,
                   max_seconds: Optional[float] = None) -> CodeBank:
    r"""At least :obj:`windows` training windows banked: batches of
    ``loader_for_epoch(epoch)`` for epochs 0, 1, ... (each epoch of the
    endless zoo draws new rigs and clips) coded by ``module``'s frozen
    autoencoder; fewer where :obj:`max_seconds` runs out first (the batch
    in hand is kept, so at least one is).

    Args:
        module: A :class:`~satagraph.lightning.TextToMotionModule` (its
            :meth:`~satagraph.lightning.TextToMotionModule.bank_batch`).
        loader_for_epoch (callable): Epoch -> iterable of
            :class:`~satagraph.data.FrameBatch`.
        windows (int): Windows wanted.
        progress (callable, optional): Called with the count so far.
        max_seconds (float, optional): Stop drawing after this long.

    Raises:
        DrawInterrupted: Ctrl-C after a batch was coded, holding the bank of
            the batches coded (before any, the plain :class:`KeyboardInterrupt`).
    """
    parts: List[CodeBank] = []
    try:
        _draw(module, loader_for_epoch, windows, parts, progress, max_seconds)
    except KeyboardInterrupt:
        if not parts:
            raise
        raise DrawInterrupted(concat_banks(parts)) from None
    return concat_banks(parts)


def _draw(module: Any, loader_for_epoch: Any, windows: int, parts: List[CodeBank],
          progress: Optional[Any], max_seconds: Optional[float]) -> None:
    """:func:`draw_code_bank`'s loop, appending each coded batch to
    :obj:`parts` as it goes (what an interrupt keeps)."""
    count, epoch = 0, 0
    deadline = None if max_seconds is None else time.monotonic() + max_seconds
    fingerprint = autoencoder_fingerprint(module.autoencoder)  # once: it hashes every weight
    with torch.no_grad():
        while count < windows:
            before = count
            for batch in loader_for_epoch(epoch):
                parts.append(module.bank_batch(batch, fingerprint))
                count += len(parts[-1])
                if progress is not None:
                    progress(count)
                if count >= windows or (deadline is not None
                                        and time.monotonic() >= deadline):
                    break
            if count == before:
                raise ValueError("the training loader gave no windows")
            if deadline is not None and time.monotonic() >= deadline:
                break
            epoch += 1


__all__ = ["CodeBank", "CodeBatch", "DrawInterrupted", "HUMAN_WORDS", "RIG_WINDOWS",
           "autoencoder_fingerprint", "captured_rigs", "check_swap_share", "concat_banks",
           "draw_code_bank", "skeleton_keys", "swap_skeletons"]
