"""Text-to-motion evaluation you can trust (issue 19, item 8).

An evaluator independent of the generator and of SATA's encoder: a small
text-motion contrastive model (offline text encoder -> MLP; the
skeleton-agnostic kinematic descriptor of
:mod:`satagraph.pipelines.motion_descriptor` -> MLP; InfoNCE), trained,
seeded, on the captioned TRAINING split only (endless-zoo training clips;
bandai / cmu / ccbase files of the manifest's train split, less one take in
five of bandai's, kept apart as seen-style test prompts). It scores, per
group of test prompts (zoo test seeds; bandai seen styles; bandai unseen
styles giant and sad):

- **real**: the test motions with their own captions;
- **shuffled captions**: the same, captions permuted (chance control);
- **retrieval (own rig)**: the nearest training clip by caption embedding,
  taken on its own rig; with ``--ckpt`` also **retrieval (retargeted)**:
  that clip retargeted through the generator's frozen SATA-RVQ onto the
  test clip's rig and cut to its length (the baseline a generator must
  beat on a rig it is asked for);
- **reconstruction** / **generator** (with ``--ckpt``): the test motion sent
  through the generator's frozen SATA-RVQ; a generation for the caption on
  the test clip's rig, given the test clip's length (stated in the table).

These rows decode with ``carriage="never"`` whatever ``--carriage`` says
(:func:`scored`): the only frames of a test rig here are the test clip's
own, and carrying a motion as its character would take its mean pose from
the very clip it is scored against. The per-skeleton probes, whose
skeletons' clips are no prompt's answer, decode as ``generate`` does.

Metrics (:mod:`satagraph.metrics.generation`): R@1/2/3 in pools of 32 and
FID / KID, each with a 95% half-width over replications; matching score,
diversity, multimodality (generator: 2 seeds per text, first 16 texts). Kinematic probes
on every group's motions: direction of travel (walk / back / left / right),
Froude speed ordering walk < run < dash, stillness of bow and bye, how far
forward motions travel off the body's facing (``sideways``, median degrees:
a crabwise walk), how fast their facing turns (``turn``, median degrees
a second: real forward walks and runs turn 2-3) and how much faster they
move over their last third than their first (``pace drift``, the signed
median: real clips 0-8 %); and the same probes per
skeleton (one rig a body plan, real rigs too), every probe prompt with
``--probe-seeds`` seeds (6: 24 walking generations a skeleton).

    python benchmarks/t2m.py [--ckpt runs/t2m_tiny/checkpoints/last.ckpt] [--quick]
        [--reference builtin] [--prompts val] [--guidance G] [--temperature T]

    python benchmarks/t2m.py --data FOLDER --ckpt C [--split test] [--pool-size N]

``--data`` scores your own captioned folder (a generator fine-tuned with
``satagraph train finetune_t2m_builtin --data FOLDER``) instead of the
project's data: its held-out split's captioned windows (``--split``, as
``satagraph train`` splits it: a manifest's split column, else 80/10/10 by
file name) are the only test prompts, and the evaluator learns from the
zoo's training clips and the folder's ``train`` split. The table says which
data and pool size it used (``--pool-size``, 32 by default; R@k needs as
many held-out windows); a split without captions, with fewer windows than
the pool or a file the evaluator cannot read (no limb on its rig) is
refused in one line. It writes ``t2m_data.*`` (``t2m_quick_data.*``).

``--prompts val`` scores the zoo's validation seeds instead of the test
prompts (no Bandai groups): choose sampling settings there and report them
on the test prompts. ``--reference`` adds a row of the test motion through
a plain autoencoder (e.g. the built-in model).

Writes ``benchmarks/results/t2m.md`` and ``.json`` (``--quick``:
``t2m_quick.*``), and the evaluator to ``runs/t2m_evaluator/``.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from collections import Counter
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np
import torch
from torch import nn

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from satagraph.data.dataset import _frames, try_load_features  # noqa: E402
from satagraph.data.captioned import FileCaptionWindows  # noqa: E402
from satagraph.data.features import (MotionFeatures, features_to_motion,  # noqa: E402
                                     integrate_root, motion_to_features)
from satagraph.datasets.captions import captions_for  # noqa: E402
from satagraph.datasets.sources import read_manifest, resolve_sources, select  # noqa: E402
from satagraph.datasets.zoo.endless import EndlessZoo  # noqa: E402
from satagraph.datasets.zoo_captions import ZooClip, dashes  # noqa: E402
from satagraph.metrics.generation import (POOL_SIZE, diversity, fid, kid,  # noqa: E402
                                          matching_score, multimodality, r_precision,
                                          replicate, subsample)
from satagraph.motion import Motion  # noqa: E402
from satagraph.pipelines.generate import (GenerationSettings, decode_on,  # noqa: E402
                                          encode_windows, generate_on, load_generator,
                                          rig_inputs)
from satagraph.nn.generators.sampling import GUIDES  # noqa: E402
from satagraph.pipelines.inference import facing_smooth_of  # noqa: E402
from satagraph.pipelines.quality import heading_gap, lands, pace_drift, turn_rate  # noqa: E402
from satagraph.pipelines.motion_descriptor import (contact_quality,  # noqa: E402
                                                   describe_features, froude_speed,
                                                   leg_length)
from satagraph.semantics import build_text_encoder  # noqa: E402
from satagraph.semantics.limbs import limb_end_index  # noqa: E402
from satagraph.transforms.canonical import canonicalize  # noqa: E402
from satagraph.transforms.carriage import CARRIAGE_MODES  # noqa: E402
from satagraph.transforms.rest import REST_MODES  # noqa: E402
from satagraph.utils.files import atomic_write_text  # noqa: E402
from results_io import SHARED_DATA  # noqa: E402

MANIFEST = SHARED_DATA / "manifest.tsv"
SPECIES = ["biped", "quadruped", "bird", "hexapod"]
FPS = 30.0


@dataclass
class Item:
    """One captioned motion: descriptor, captions and what the probes read."""

    desc: np.ndarray
    captions: List[str]
    label: str
    group: str
    skeleton: str
    seconds: float
    froude: float
    travel: np.ndarray  # final ground displacement in the start facing frame, leg lengths
    contact: Tuple[float, float]  # foot sliding (heights/s), hovering (heights)
    sideways: float = float("nan")  # degrees between travel and facing (see sideways)
    turn: float = float("nan")  # signed degrees a second the facing turns (see turning)
    drift: float = float("nan")  # the root's pace, last third over first, minus 1 (see drifting)
    motion: Optional[Motion] = field(default=None, repr=False)


def measure(feats: MotionFeatures, captions: List[str], label: str, group: str,
            skeleton: str, keep: bool = False) -> Item:
    """An :class:`Item` of canonical features (the motion kept for targets)."""
    ends = limb_end_index(feats.skeleton)
    _, origin = integrate_root(feats.r[1:], feats.fps)
    leg = max(leg_length(feats.skeleton, ends, feats.height), 1e-6)
    travel = (origin[-1] - origin[0])[[0, 2]] / leg
    motion = features_to_motion(feats)
    return Item(describe_features(feats, ends), captions, label, group, skeleton,
                feats.num_frames / feats.fps, froude_speed(feats, ends), travel,
                contact_quality(feats), sideways(motion), turning(motion),
                drifting(motion), motion if keep else None)


def _or_nan(value: Optional[float]) -> float:
    return float("nan") if value is None else float(value)


def sideways(motion: Motion) -> float:
    """:func:`~satagraph.pipelines.quality.heading_gap` of a canonical
    motion, unsigned: degrees between where it travels and where its body
    faces (a crabwise walk); NaN where it has none."""
    return abs(_or_nan(heading_gap(motion)))


def turning(motion: Motion) -> float:
    """:func:`~satagraph.pipelines.quality.turn_rate` of a canonical motion
    (signed degrees a second, positive to the left); NaN where it has none."""
    return _or_nan(turn_rate(motion))


def drifting(motion: Motion) -> float:
    """:func:`~satagraph.pipelines.quality.pace_drift` of a canonical motion
    (how much faster it moves over its last third than its first); NaN
    where it has none."""
    return _or_nan(pace_drift(motion))


def zoo_items(stream: str, count: int, seed: int = 0, keep: bool = False) -> List[Item]:
    """Endless-zoo clips of 32-96 frames of one seed stream, captioned from
    their facts."""
    zoo, rng = EndlessZoo(SPECIES, fps=FPS, seed=seed), np.random.default_rng([seed, 8])
    out = []
    for idx in range(count):
        sample = zoo.sample(0, idx, int(rng.integers(33, 97)), stream, False)
        motion = canonicalize(sample.motion, fps=FPS, up_axis="+Y", unit_scale=1.0)
        caps = [c.text for c in captions_for(sample)]
        out.append(measure(motion_to_features(motion), caps, zoo_label(sample), "zoo",
                           sample.species, keep))
    return out


def zoo_label(sample) -> str:
    """A zoo clip's label in the probes' (bandai's) vocabulary where it has
    one: ``back`` walks are ``walk-back``, ``side`` walks ``walk-left`` /
    ``walk-right`` by the side they travel to, ``run`` clips ``dash`` where
    their captions say so; other kinds keep their name."""
    facts = sample.facts
    if sample.kind == "back":
        return "walk-back"
    if sample.kind == "side" and facts is not None:
        return "walk-left" if facts.travel > 0 else "walk-right"
    if sample.kind == "run" and facts is not None:
        return "dash" if dashes(ZooClip.of(facts)) else "run"
    return sample.kind


def bandai_parts(path: str) -> Tuple[str, str]:
    """(action, style) of a bandai file name."""
    parts = Path(path).stem.split("_")
    return parts[1], parts[2]


#: Frames of the captioned windows cut from files, and between their starts.
WINDOW, STRIDE = 96, 48


def file_items(files, group: Callable[[object], str], window: int = WINDOW,
               stride: int = STRIDE, keep: bool = False) -> List[Item]:
    """Captioned windows of manifest files (see :class:`FileCaptionWindows`)."""
    kept, feats, errors = try_load_features(files, {"fps": FPS})
    for err in errors:
        print("skipped:", err, file=sys.stderr)
    return window_items(FileCaptionWindows(kept, feats, window, stride), group, keep)


def window_items(windows: FileCaptionWindows, group: Callable[[object], str],
                 keep: bool = False) -> List[Item]:
    """An :class:`Item` of every captioned window (labelled with the Bandai
    action, else the dataset; the skeleton id of
    :func:`~satagraph.data.dataset.skeleton_id`: a rig of its own in a
    folder that names none)."""
    out = []
    for i, start in windows.index:
        f, full = windows.files[i], windows.features[i]
        part = _frames(full, slice(start, min(start + windows.window, full.num_frames)))
        caps = [c.text for c in windows.window_captions(i, start)]
        label = bandai_parts(f.path)[0] if f.dataset == "bandai" else f.dataset
        out.append(measure(part, caps, label, group(f), windows.skeletons[i], keep))
    return out


def file_splits(files) -> Dict[str, List[object]]:
    """The captioned manifest files by role: ``fit``, what the evaluator
    learns from (every Bandai training take but one in five, CMU and
    CC_Base); ``seen``, the Bandai training takes held out of it (seen-style
    test prompts); ``test``, Bandai's test takes (unseen styles); ``val``,
    Bandai's validation takes (``--bandai-val``)."""
    train = sorted(select(files, "train"), key=lambda f: f.path)
    seen = {f.path for f in [f for f in train if f.dataset == "bandai"][::5]}
    return {"fit": [f for f in train if f.path not in seen],
            "seen": [f for f in train if f.path in seen],
            "test": [f for f in select(files, "test") if f.dataset == "bandai"],
            "val": [f for f in select(files, "val") if f.dataset == "bandai"]}


def captioned_files():
    """The manifest's files with captions of their own."""
    return [f for f in read_manifest(MANIFEST) if f.dataset in ("bandai", "cmu", "ccbase")]


def bandai_val_items(zoo_train: List[Item]) -> Tuple[List[Item], List[Item]]:
    """For ``--prompts val --bandai-val``: the items of the test table's
    evaluator (:obj:`zoo_train` and the ``fit`` files of :func:`file_splits`)
    and Bandai's validation takes (never trained on and never a test
    prompt), for a rule to see a real human rig."""
    split = file_splits(captioned_files())
    return (zoo_train + file_items(split["fit"], lambda f: f.dataset, keep=True),
            file_items(split["val"], lambda f: "bandai (val)", keep=True))


def real_items(quick: bool, seed: int, prompts: str = "test") -> Tuple[List[Item], List[Item]]:
    """Training items (evaluator, retrieval) and test items (:obj:`prompts`
    ``"val"``: the zoo's validation seeds instead, and no file groups, for
    choosing sampling settings away from the test prompts)."""
    zoo_train = zoo_items("train", 128 if quick else 1200, seed, keep=True)
    zoo_test = zoo_items(prompts, 64 if quick else 256, seed, keep=True)
    if quick or prompts != "test" or not MANIFEST.is_file():
        return zoo_train, zoo_test
    split = file_splits(captioned_files())
    train_items = zoo_train + file_items(split["fit"], lambda f: f.dataset, keep=True)
    test_items = (zoo_test + file_items(split["seen"], lambda f: "bandai seen-style", keep=True)
                  + file_items(split["test"], lambda f: "bandai unseen-style", keep=True))
    return train_items, test_items


@dataclass
class Folder:
    """A user's captioned folders (``--data``): the captioned windows of
    their training split (the evaluator learns from them, beside the zoo's)
    and of the held-out split scored, with what the table states of them."""

    fit: List[Item]
    test: List[Item]
    facts: Dict[str, object]


def folder_items(sources: Sequence[str], split: str, pool_size: int) -> Folder:
    """The captioned windows of :obj:`sources` (folders or manifests, split
    as ``satagraph train --data`` splits them) for :func:`evaluate`.

    Raises:
        ValueError: One line naming the source or file: no file in
            :obj:`split`, a file that cannot be read or whose rig shows the
            evaluator no limb, no caption sidecar in :obj:`split`, or fewer
            captioned windows there than :obj:`pool_size`.
    """
    files = resolve_sources(list(sources))
    where = ", ".join(sources)
    held = [f for f in files if f.split == split]
    if not held:
        raise ValueError(f"{where}: no file in the {split!r} split to score (a manifest's "
                         "split column; a folder without one is split 80/10/10 by file "
                         "name: try another --split)")
    test = readable_windows(held)
    if not test.index:
        raise ValueError(f"{where}: none of the {len(held)} files of the {split!r} split has "
                         "a caption (a sidecar CLIP.txt of HumanML3D lines "
                         "caption#tokens#from#to, or CLIP.json, beside CLIP.bvh)")
    if len(test.index) < pool_size:
        smaller = (f" or pass --pool-size {len(test.index)} or less" if len(test.index) >= 4
                   else " (4 windows at least)")
        raise ValueError(f"{where}: {len(test.index)} captioned windows of {WINDOW} frames in "
                         f"the {split!r} split ({len(test.files)} files), fewer than the pool "
                         f"size {pool_size} R-precision ranks each caption in: hold out more "
                         f"clips{smaller}")
    fit = readable_windows([f for f in files if f.split == "train"])
    fit_items = window_items(fit, lambda f: f.dataset, keep=True)
    test_items = window_items(test, lambda f: f"{f.dataset} ({split})", keep=True)
    facts = {"data": list(sources), "split": split, "window": WINDOW,
             "test_files": len(test.files), "test_uncaptioned": len(test.uncaptioned),
             "fit_files": len(fit.files), "fit_windows": len(fit_items)}
    return Folder(fit_items, test_items, facts)


def readable_windows(files) -> FileCaptionWindows:
    """The captioned windows of :obj:`files`, each of which must load and
    show the evaluator a limb (:func:`measure` reads motion by the limbs'
    ends).

    Raises:
        ValueError: One line naming the first file that does not.
    """
    kept, feats, errors = try_load_features(files, {"fps": FPS})
    if errors:
        more = f"; and {len(errors) - 1} more files" if len(errors) > 1 else ""
        raise ValueError(f"{errors[0]} (the evaluator reads every file{more})")
    for f, full in zip(kept, feats):
        if max(limb_end_index(full.skeleton)) < 0:
            raise ValueError(f"{f.path}: the evaluator finds no limb on its rig "
                             f"({full.skeleton.num_joints} joints; it reads motion by the "
                             "ends of the legs and arms its joint names show, see satagraph "
                             "tags), so it cannot score it: leave it out or name its joints")
    return FileCaptionWindows(kept, feats, WINDOW, STRIDE)


class Evaluator(nn.Module):
    """Text and motion MLPs into one unit-norm space.

    Shapes:
        - **text**: :math:`(N, D_t)`; **desc**: :math:`(N, D_m)`
        - **output**: :math:`(N, E)`
    """

    def __init__(self, text_dim: int, desc_dim: int, width: int = 128, out: int = 64) -> None:
        super().__init__()
        self.text = nn.Sequential(nn.Linear(text_dim, width), nn.GELU(), nn.Linear(width, out))
        self.motion = nn.Sequential(nn.Linear(desc_dim, width), nn.GELU(),
                                    nn.Dropout(0.1), nn.Linear(width, out))
        self.register_buffer("mean", torch.zeros(desc_dim))
        self.register_buffer("std", torch.ones(desc_dim))

    def embed_text(self, text: torch.Tensor) -> torch.Tensor:
        return nn.functional.normalize(self.text(text), dim=-1)

    def embed_motion(self, desc: torch.Tensor) -> torch.Tensor:
        return nn.functional.normalize(self.motion((desc - self.mean) / self.std), dim=-1)


def train_evaluator(items: Sequence[Item], encode: Callable, steps: int, seed: int,
                    batch: int = 64, temperature: float = 0.1) -> Evaluator:
    """InfoNCE on (caption drawn per step, descriptor) pairs of the training
    items; descriptors standardised with the training statistics."""
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    desc = torch.tensor(np.stack([it.desc for it in items]), dtype=torch.float32)
    texts = sorted({c for it in items for c in it.captions})
    lookup = {t: i for i, t in enumerate(texts)}
    text_emb = encode(texts)
    model = Evaluator(text_emb.shape[1], desc.shape[1])
    model.mean.copy_(desc.mean(0))
    model.std.copy_(desc.std(0).clamp_min(1e-3))
    opt = torch.optim.AdamW(model.parameters(), lr=2e-3, weight_decay=1e-4)
    for _ in range(steps):
        idx = rng.choice(len(items), size=min(batch, len(items)), replace=False)
        caps = [lookup[items[i].captions[rng.integers(len(items[i].captions))]] for i in idx]
        logits = model.embed_motion(desc[idx]) @ model.embed_text(text_emb[caps]).T
        target = torch.arange(len(idx))
        loss = (nn.functional.cross_entropy(logits / temperature, target)
                + nn.functional.cross_entropy(logits.T / temperature, target)) / 2
        opt.zero_grad()
        loss.backward()
        opt.step()
    return model.eval()


class Recogniser(nn.Module):
    """An action classifier on standardised descriptors (bandai actions,
    zoo kinds), trained on the training items.

    Shapes:
        - **desc**: :math:`(N, D_m)`
        - **output**: :math:`(N, C)` logits
    """

    def __init__(self, desc_dim: int, labels: Sequence[str], width: int = 128) -> None:
        super().__init__()
        self.labels = list(labels)
        self.net = nn.Sequential(nn.Linear(desc_dim, width), nn.GELU(), nn.Dropout(0.1),
                                 nn.Linear(width, len(self.labels)))
        self.register_buffer("mean", torch.zeros(desc_dim))
        self.register_buffer("std", torch.ones(desc_dim))

    def forward(self, desc: torch.Tensor) -> torch.Tensor:
        return self.net((desc - self.mean) / self.std)

    def predict(self, descs: Sequence[np.ndarray], labels: Sequence[str]
                ) -> List[Tuple[str, str]]:
        """``(asked, recognised)`` label pairs of the motions whose asked
        label it knows."""
        known = [(d, l) for d, l in zip(descs, labels) if l in self.labels]
        if not known:
            return []
        with torch.no_grad():
            pred = self(torch.tensor(np.stack([d for d, _ in known]),
                                     dtype=torch.float32)).argmax(1).tolist()
        return [(l, self.labels[p]) for p, (_, l) in zip(pred, known)]

    def accuracy(self, descs: Sequence[np.ndarray], labels: Sequence[str]) -> Optional[float]:
        """Share of motions (of a label it knows) classified as the label
        their prompt asks for."""
        pairs = self.predict(descs, labels)
        return float(np.mean([a == b for a, b in pairs])) if pairs else None

    def accuracy_interval(self, descs: Sequence[np.ndarray], labels: Sequence[str]
                          ) -> Optional[Tuple[float, float]]:
        """:meth:`accuracy` and its 95 % half-width over the motions
        (normal approximation of a binomial share: with 256 motions at
        0.45 it is 0.06, so two generators closer than that are not told
        apart by it)."""
        pairs = self.predict(descs, labels)
        if not pairs:
            return None
        share = float(np.mean([a == b for a, b in pairs]))
        return share, 1.96 * math.sqrt(share * (1.0 - share) / len(pairs))

    def by_label(self, descs: Sequence[np.ndarray], labels: Sequence[str]
                 ) -> Dict[str, Dict[str, object]]:
        """Per asked label: ``n``, the share recognised as it and the label
        recognised most often instead (the first met among equals; ``None``
        when never wrong)."""
        out: Dict[str, Dict[str, object]] = {}
        pairs = self.predict(descs, labels)
        for asked in sorted(set(labels)):
            got = [b for a, b in pairs if a == asked]
            if not got:
                continue
            wrong = Counter(b for b in got if b != asked)
            out[asked] = {"n": len(got), "accuracy": 1.0 - sum(wrong.values()) / len(got),
                          "instead": wrong.most_common(1)[0][0] if wrong else None}
        return out


def train_recogniser(items: Sequence[Item], steps: int, seed: int,
                     batch: int = 64) -> Recogniser:
    """Cross-entropy on the training items' labels."""
    torch.manual_seed(seed)
    rng = np.random.default_rng([seed, 1])
    desc = torch.tensor(np.stack([it.desc for it in items]), dtype=torch.float32)
    model = Recogniser(desc.shape[1], sorted({it.label for it in items}))
    target = torch.tensor([model.labels.index(it.label) for it in items])
    model.mean.copy_(desc.mean(0))
    model.std.copy_(desc.std(0).clamp_min(1e-3))
    opt = torch.optim.AdamW(model.parameters(), lr=2e-3, weight_decay=1e-4)
    for _ in range(steps):
        idx = torch.from_numpy(rng.choice(len(items), size=min(batch, len(items)),
                                          replace=False))
        loss = nn.functional.cross_entropy(model(desc[idx]), target[idx])
        opt.zero_grad()
        loss.backward()
        opt.step()
    return model.eval()


def embed(model: Evaluator, encode: Callable, captions: Sequence[str],
          descs: Sequence[np.ndarray]) -> Tuple[np.ndarray, np.ndarray]:
    """Text and motion embeddings (numpy) of paired captions and descriptors."""
    with torch.no_grad():
        t = model.embed_text(encode(list(captions))).double().numpy()
        m = model.embed_motion(torch.tensor(np.stack(descs), dtype=torch.float32))
    return t, m.double().numpy()


def score(model: Evaluator, encode: Callable, captions: List[str], descs: List[np.ndarray],
          reference: np.ndarray, reps: int, groups: Optional[List[np.ndarray]] = None,
          pool_size: int = POOL_SIZE) -> Dict[str, object]:
    """Every metric of one row (``reference``: the real motions' embeddings;
    R@k in pools of :obj:`pool_size`)."""
    text, motion = embed(model, encode, captions, descs)
    row: Dict[str, object] = {"n": len(captions)}
    if len(captions) >= pool_size:
        for k in range(3):
            row[f"R@{k + 1}"] = replicate(
                lambda rng: float(r_precision(text, motion, 3, pool_size, rng)[k]), reps)
    row["matching"] = matching_score(text, motion)
    row.update(fid_kid(motion, reference, reps))
    row["diversity"] = diversity(motion, 300)
    if groups:
        row["multimodality"] = multimodality(
            [embed(model, encode, ["x"] * len(g), list(g))[1] for g in groups], 10)
    return row


def split_halves(x: np.ndarray, rng: np.random.Generator) -> Tuple[np.ndarray, np.ndarray]:
    """Two random halves of the rows."""
    order = rng.permutation(len(x))
    return x[order[: len(x) // 2]], x[order[len(x) // 2:]]


def fid_kid(motion: np.ndarray, reference: Optional[np.ndarray], reps: int
            ) -> Dict[str, Tuple[float, float]]:
    """FID and KID (mean, 95% half-width over :obj:`reps` draws) of half of
    the motions against half of the reference; for the real row
    (:obj:`reference` ``None``), one random half of it against the other,
    so that every row compares sets of the same size."""
    def draw(fn):
        def once(rng):
            if reference is None:
                return fn(*split_halves(motion, rng))
            half = len(motion) // 2
            return fn(subsample(reference, half, rng), subsample(motion, half, rng))
        return replicate(once, reps)
    return {"fid": draw(fid), "kid": draw(kid)}


def retrieve(train: Sequence[Item], captions: Sequence[str], encode: Callable) -> List[Item]:
    """The training item whose caption is nearest (cosine of the text
    encoder) to each caption."""
    pool = [(c, it) for it in train for c in it.captions]
    keys = nn.functional.normalize(encode([c for c, _ in pool]), dim=-1)
    query = nn.functional.normalize(encode(list(captions)), dim=-1)
    best = (query @ keys.T).argmax(dim=1).tolist()
    return [pool[b][1] for b in best]


def travel_direction(travel: np.ndarray) -> str:
    """forward / back / left / right: the larger component of the ground
    displacement (x: left, z: forward)."""
    x, z = float(travel[0]), float(travel[1])
    if abs(z) >= abs(x):
        return "forward" if z > 0 else "back"
    return "left" if x > 0 else "right"


#: Bandai action -> direction of travel it asks for (walk-left / -right
#: are "forward and to the left / right": their lateral sign is what counts).
DIRECTIONS = {"walk": "forward", "walk-back": "back", "walk-left": "left",
              "walk-right": "right"}
STILL_FROUDE = 0.1
#: Seeds of every per-skeleton probe prompt: 6 give 24 walking generations a
#: skeleton (one case moves its direction by 4 points; with 2 it was 12.5).
PROBE_SEEDS = 6


def direction_ok(label: str, travel: np.ndarray) -> bool:
    """Whether a motion travels the way its action asks."""
    want = DIRECTIONS[label]
    if want in ("left", "right"):
        return (travel[0] > 0) == (want == "left")
    return travel_direction(travel) == want


#: Actions that travel the way the body faces (:func:`sideways` is read on them).
FORWARD = ("walk", "run", "dash")
#: The probe actions that travel (``lands`` is read over them).
TRAVELLING = tuple(DIRECTIONS) + FORWARD[1:]


def _forward_median(labels: Sequence[str], values: Optional[Sequence[float]],
                    signed: bool = False) -> Optional[Tuple[float, int]]:
    """Median and count of the finite magnitudes of :obj:`values` (the
    values themselves with :obj:`signed`) over the forward actions
    (:data:`FORWARD`); ``None`` where there are none."""
    if values is None:
        return None
    ahead = [v if signed else abs(v) for l, v in zip(labels, values)
             if l in FORWARD and np.isfinite(v)]
    return (float(np.median(ahead)), len(ahead)) if ahead else None


def _left_share(labels: Sequence[str], turns: Sequence[float]) -> float:
    """Share of the forward actions' turns that go left: about half for a
    mirror-symmetric generator (``experiments/T2M.md`` section 31)."""
    ahead = [v for l, v in zip(labels, turns) if l in FORWARD and np.isfinite(v)]
    return float(np.mean([v > 0 for v in ahead]))


def probes(labels: Sequence[str], travels: Sequence[np.ndarray],
           froudes: Sequence[float], gaps: Optional[Sequence[float]] = None,
           turns: Optional[Sequence[float]] = None,
           drifts: Optional[Sequence[float]] = None) -> Dict[str, object]:
    """Direction accuracy, walk < run < dash ordering of mean Froude speed,
    share of still bow / bye motions and, with :obj:`gaps` (:func:`sideways`
    per motion) and :obj:`turns` (:func:`turning`), their median magnitude
    over the forward actions (:data:`FORWARD`) and the share of those turns
    that go left, and with :obj:`drifts` (:func:`drifting`) their median
    signed pace drift, over labelled motions."""
    out: Dict[str, object] = {}
    for key, values in (("sideways", gaps), ("turn", turns)):
        found = _forward_median(labels, values)
        if found is not None:
            out[key] = found
    if "turn" in out:
        out["turn_left"] = _left_share(labels, turns)
    drift = _forward_median(labels, drifts, signed=True)
    if drift is not None:
        out["drift"] = drift
    dirs = [direction_ok(l, t) for l, t in zip(labels, travels) if l in DIRECTIONS]
    if dirs:
        out["direction"] = (float(np.mean(dirs)), len(dirs))
    speed = {a: float(np.mean([f for l, f in zip(labels, froudes) if l == a]))
             for a in ("walk", "run", "dash") if a in labels}
    if len(speed) == 3:
        out["speeds"] = speed
        out["ordering"] = speed["walk"] < speed["run"] < speed["dash"]
    still = [f < STILL_FROUDE for l, f in zip(labels, froudes) if l in ("bow", "bye")]
    if still:
        out["still"] = (float(np.mean(still)), len(still))
    return out


def scored(settings: Optional[GenerationSettings]) -> GenerationSettings:
    """:obj:`settings` (default: ``generate``'s) for the rows scored
    against their test clips: never carried as the character
    (``carriage="never"``), whose only frames here are the test clip's own."""
    return replace(settings or GenerationSettings(), carriage="never")


def generated_items(module, items: Sequence[Item], seeds: int,
                    settings: Optional[GenerationSettings] = None) -> List[List[Item]]:
    """Per seed, one generation per test item on its own rig, of its length
    (the ground-truth length is given), with the sampling :obj:`settings`
    (default: :class:`~satagraph.pipelines.generate.GenerationSettings`),
    never carried as the character (:func:`scored`)."""
    settings = scored(settings)
    out = []
    for seed in range(seeds):
        row = []
        for it in items:
            motion = generate_on(module, it.captions[0], it.motion, it.seconds, seed, settings)
            feats = motion_to_features(canonicalize(motion, fps=FPS))
            row.append(measure(feats, it.captions, it.label, it.group, it.skeleton))
        out.append(row)
    return out


def transfer(module, source: Motion, target: Motion,
             settings: Optional[GenerationSettings] = None) -> MotionFeatures:
    """:obj:`source` through the generator's frozen SATA-RVQ: its codes on
    its own rig, decoded on :obj:`target`'s rig as :obj:`settings` decode
    generated motion (:func:`~satagraph.pipelines.generate.decode_on`;
    canonical features), never carried as the character (:func:`scored`);
    both in the RVQ's training windows."""
    settings = scored(settings)
    with torch.no_grad():
        rig = rig_inputs(module, source)
        feats = motion_to_features(rig.shown, facing_smooth=facing_smooth_of(module))
        codes = encode_windows(module.autoencoder, feats, rig.semantic)
        motion = decode_on(module, codes, rig_inputs(module, target), settings)
    return motion_to_features(canonicalize(motion, fps=FPS))


def reconstructed_items(module, items: Sequence[Item],
                        settings: Optional[GenerationSettings] = None) -> List[Item]:
    """Every test item sent through the generator's frozen SATA-RVQ (codes
    of the whole window, decoded on its own rig)."""
    return [measure(transfer(module, it.motion, it.motion, settings), it.captions, it.label, it.group,
                    it.skeleton) for it in items]


def autoencoded_items(autoencoder, items: Sequence[Item]) -> List[Item]:
    """Every test item encoded and decoded on its own rig by a plain
    autoencoder (``--reference``: the ceiling an RVQ started from it could
    reach), put on the floor as the other rows; one reading, as the RVQ's
    own row decodes its codes once (no mirror image)."""
    from satagraph.pipelines.inference import reconstruct_motion
    out = []
    for it in items:
        with torch.no_grad():
            motion = reconstruct_motion(autoencoder, it.motion, autoencoder.embed, ground=True,
                                        mirror=False, two_rests=False)
        feats = motion_to_features(canonicalize(motion, fps=FPS))
        out.append(measure(feats, it.captions, it.label, it.group, it.skeleton))
    return out


def retargeted_items(module, retrieved: Sequence[Item], items: Sequence[Item],
                     settings: Optional[GenerationSettings] = None) -> List[Item]:
    """Each retrieved training clip, cut to its test item's length,
    retargeted onto the test item's rig through the frozen SATA-RVQ."""
    out = []
    for got, it in zip(retrieved, items):
        frames = min(got.motion.num_frames, it.motion.num_frames)
        feats = transfer(module, got.motion.slice(0, frames), it.motion, settings)
        out.append(measure(feats, it.captions, it.label, it.group, it.skeleton))
    return out


#: Probe prompts (``{}``: the subject) and the action each asks for.
PROBE_PROMPTS: Tuple[Tuple[str, str], ...] = (
    ("{} walks forward", "walk"), ("{} walks backward", "walk-back"),
    ("{} walks forward and to the left", "walk-left"),
    ("{} walks forward and to the right", "walk-right"), ("{} runs forward", "run"),
    ("{} dashes forward", "dash"), ("{} bows", "bow"),
    ("{} waves goodbye with one hand", "bye"))
SUBJECTS = {"biped": "a person", "quadruped": "a quadruped", "bird": "a bird",
            "hexapod": "an insect", "human": "a person", "dog": "a four-legged animal"}


def skeleton_targets(test: Sequence[Item], quick: bool,
                     split: str = "test") -> Dict[str, Tuple[str, Motion]]:
    """One target per skeleton: the first zoo rig of :obj:`test` (the
    test or validation items) of every body plan, the first bandai rig, the
    first of every other rig (``--data``), and cmu 01_01 and a dog clip of
    the manifest's :obj:`split` (name -> (subject, canonical motion))."""
    out: Dict[str, Tuple[str, Motion]] = {}
    for it in test:
        key = (f"zoo {it.skeleton}" if it.group == "zoo"
               else "bandai" if it.group.startswith("bandai") else it.skeleton)
        if it.motion is not None and key not in out:
            out[key] = (SUBJECTS.get(it.skeleton, "a person"), it.motion)
    if quick or not MANIFEST.is_file():
        return out
    files = read_manifest(MANIFEST)
    for name, subject, dataset in (("cmu 01_01", "a person", "cmu"), ("dog", SUBJECTS["dog"],
                                                                        "dog")):
        motion = (manifest_motion(files, dataset, split) if split == "test" or dataset != "dog"
                  else standing_dog(files, split))
        if motion is not None:
            out[name] = (subject, motion)
    return out


def standing_dog(files, split: str) -> Optional[Motion]:
    """The first dog clip of the manifest's :obj:`split` that ``down`` can
    be read against: some paw it stands on
    (:func:`~satagraph.pipelines.quality.stood_on`), read from its lowest
    point (y = 0), as when ``experiments/T2M.md`` section 93 chose its
    validation dog (``D1_009_KAN01_001``; ``lands`` now reads each clip
    from the floor it stands on, and would take the first validation
    clip, ``D1_031``)."""
    from satagraph.pipelines.quality import standing_shares, stood_on
    for f in files:
        if f.dataset != "dog" or f.split != split:
            continue
        motion = manifest_motion([f], "dog", split)
        if motion is not None and stood_on(standing_shares(motion)):
            return motion
    return None


def manifest_motion(files, dataset: str, split: str, path_part: str = "") -> Optional[Motion]:
    """The canonical motion (at :data:`FPS`) of the first manifest file of a
    dataset's split whose path contains :obj:`path_part` (the dog's files,
    which do not say their units, read in centimetres); ``None`` if none
    loads."""
    picks = [f for f in files if f.dataset == dataset and f.split == split
             and path_part in f.path][:1]
    if dataset == "dog":
        picks = [replace(f, scale=0.01) for f in picks]
    _, feats, _ = try_load_features(picks, {"fps": FPS})
    return features_to_motion(feats[0]) if feats else None


def skeleton_probes(module, targets: Dict[str, Tuple[str, Motion]], seeds: int,
                    seconds: float = 4.0, settings: Optional[GenerationSettings] = None
                    ) -> List[Dict[str, object]]:
    """The generator's probes per skeleton: every probe prompt, :obj:`seeds`
    seeds, :obj:`seconds` long, and over the prompts that travel
    (:data:`TRAVELLING`) the median ``lands`` of their motions against the
    target's own clip (:func:`~satagraph.pipelines.quality.lands`: 0 where a
    limb that clip stands on never comes down, a dog's forepaws carried
    like hands)."""
    settings = settings or GenerationSettings()
    rows = []
    for name, (subject, target) in targets.items():
        labels, travels, froudes, gaps, turns, drifts, down = [], [], [], [], [], [], []
        own = canonicalize(target, fps=FPS)
        for prompt, label in PROBE_PROMPTS:
            for seed in range(seeds):
                motion = canonicalize(generate_on(module, prompt.format(subject), target,
                                                  seconds, seed, settings), fps=FPS)
                it = measure(motion_to_features(motion), [], label, name, name)
                labels.append(label), travels.append(it.travel), froudes.append(it.froude)
                gaps.append(it.sideways), turns.append(it.turn), drifts.append(it.drift)
                down.append(lands(motion, own) if label in TRAVELLING else None)
        found = probes(labels, travels, froudes, gaps, turns, drifts)
        kept = [d for d in down if d is not None]
        if kept:  # the target's own clip stands on some limb in half its frames
            found["lands"] = (float(np.median(kept)), len(kept))
        rows.append({"skeleton": name, "subject": subject, "probes": found})
    return rows


def group_rows(name: str, test: List[Item], train: List[Item], model: Evaluator,
               recogniser: Recogniser, encode: Callable, reps: int,
               extra: Dict[str, List[List[Item]]], seed: int,
               module=None, settings: Optional[GenerationSettings] = None,
               pool_size: int = POOL_SIZE) -> List[Dict[str, object]]:
    """The rows of one group of test prompts: real, shuffled captions,
    retrieval (on its own rig; retargeted onto the test rig when a
    generator's :obj:`module` is given) and the extra sets
    (reconstruction, generator seeds); R@k in pools of :obj:`pool_size`."""
    caps = [it.captions[0] for it in test]
    _, reference = embed(model, encode, caps, [it.desc for it in test])
    perm = np.random.default_rng(seed).permutation(len(test))
    retrieved = retrieve(train, caps, encode)
    sets = {"real": [test], "shuffled captions": [[test[i] for i in perm]],
            "retrieval (own rig)": [retrieved]}
    if module is not None:
        sets["retrieval (retargeted)"] = [retargeted_items(module, retrieved, test, settings)]
    sets.update(extra)
    rows = []
    for kind, seeds in sets.items():
        items = seeds[0]
        groups = ([np.stack([s[i].desc for s in seeds]) for i in range(min(16, len(items)))]
                  if len(seeds) > 1 else None)
        same = kind in ("real", "shuffled captions")  # the test motions themselves
        row = score(model, encode, caps, [it.desc for it in items],
                    None if same else reference, reps, groups, pool_size)
        row.update(slide=float(np.mean([it.contact[0] for it in items])),
                   hover=float(np.mean([it.contact[1] for it in items])))
        descs, labels = [it.desc for it in items], [it.label for it in test]
        row.update(group=name, row=kind, action=recogniser.accuracy_interval(descs, labels),
                   action_by_label=recogniser.by_label(descs, labels),
                   probes=probes([it.label for it in test], [it.travel for it in items],
                                 [it.froude for it in items], [it.sideways for it in items],
                                 [it.turn for it in items], [it.drift for it in items]))
        rows.append(row)
    return rows


def fmt(value, digits: int = 3) -> str:
    """A metric cell: ``mean ± half-width`` for a pair, a number, or blank."""
    if value is None:
        return ""
    if isinstance(value, (tuple, list)):
        return f"{value[0]:.{digits}f} ± {value[1]:.{digits}f}"
    return f"{value:.{digits}f}"


def probe_cell(p: Dict[str, object]) -> str:
    """The probes of a row, in words."""
    parts = []
    if "direction" in p:
        parts.append(f"dir {p['direction'][0]:.0%} (n={p['direction'][1]})")
    if "ordering" in p:
        s = p["speeds"]
        parts.append(f"walk<run<dash {'yes' if p['ordering'] else 'NO'} "
                     f"({s['walk']:.2f}/{s['run']:.2f}/{s['dash']:.2f})")
    if "still" in p:
        parts.append(f"still {p['still'][0]:.0%} (n={p['still'][1]})")
    if "sideways" in p:
        parts.append(f"sideways {p['sideways'][0]:.0f} deg (n={p['sideways'][1]})")
    if "turn" in p:
        left = f", {p['turn_left']:.0%} left" if "turn_left" in p else ""
        parts.append(f"turn {p['turn'][0]:.1f} deg/s (n={p['turn'][1]}{left})")
    if "drift" in p:
        parts.append(f"pace drift {p['drift'][0]:+.0%} (n={p['drift'][1]})")
    if "lands" in p:
        parts.append(f"down {p['lands'][0]:.2f} (n={p['lands'][1]})")
    return "; ".join(parts)


def table(rows: Sequence[Dict[str, object]]) -> str:
    """The markdown table."""
    head = ("| group | row | n | R@1 | R@2 | R@3 | matching | FID | KID | diversity | "
            "multimodality | action acc | foot slide (H/s) | hover (H) | probes |\n|"
            + "---|" * 15)
    lines = [head]
    for r in rows:
        kid = r["kid"]
        lines.append(
            f"| {r['group']} | {r['row']} | {r['n']} | {fmt(r.get('R@1'))} | "
            f"{fmt(r.get('R@2'))} | {fmt(r.get('R@3'))} | {fmt(r['matching'])} | "
            f"{fmt(r['fid'])} | {fmt(kid, 4)} | {fmt(r['diversity'])} | "
            f"{fmt(r.get('multimodality'))} | {fmt(r['action'], 2)} | "
            f"{fmt(r['slide'])} | {fmt(r['hover'], 3)} | "
            f"{probe_cell(r['probes'])} |")
    return "\n".join(lines)


def action_table(rows: Sequence[Dict[str, object]]) -> str:
    """Action accuracy per asked action of each group's rows, with the
    action recognised most often instead."""
    out = []
    for group in dict.fromkeys(r["group"] for r in rows):
        mine = [r for r in rows if r["group"] == group and r["row"] != "shuffled captions"]
        asked = list(dict.fromkeys(a for r in mine for a in r["action_by_label"]))
        if not asked:
            continue
        out += [f"\nAction accuracy per asked action, {group} (most often recognised "
                "instead):\n", "| action | n | " + " | ".join(r["row"] for r in mine) + " |",
                "|---|---:|" + "---|" * len(mine)]
        for a in asked:
            cells = []
            for r in mine:
                c = r["action_by_label"].get(a)
                cells.append("" if c is None else f"{c['accuracy']:.2f}"
                             + (f" ({c['instead']})" if c["instead"] else ""))
            n = next(r["action_by_label"][a]["n"] for r in mine if a in r["action_by_label"])
            out.append(f"| {a} | {n} | " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n" if out else ""


def cached_encoder() -> Callable[[List[str]], torch.Tensor]:
    """The offline text encoder as ``encode(texts) -> [N, D]``, each text
    encoded once."""
    encoder = build_text_encoder("offline")
    cache: Dict[str, torch.Tensor] = {}

    def encode(texts: List[str]) -> torch.Tensor:
        missing = [t for t in dict.fromkeys(texts) if t not in cache]
        if missing:
            cache.update(zip(missing, torch.as_tensor(encoder.encode(missing)).float()))
        return torch.stack([cache[t] for t in texts])
    return encode


def evaluate(quick: bool, ckpt: Optional[str], seed: int = 0, steps: Optional[int] = None,
             reps: Optional[int] = None, gen_seeds: int = 2,
             reference: Optional[str] = None, prompts: str = "test",
             settings: Optional[GenerationSettings] = None,
             probe_seeds: Optional[int] = None,
             bandai_val: bool = False, folder: Optional[Folder] = None,
             pool_size: int = POOL_SIZE) -> Tuple[List[Dict], Dict]:
    """Train the evaluator and score every group; rows and run facts
    (:obj:`reference`: an autoencoder checkpoint, ``builtin`` or a weights
    file, whose reconstruction is one more row per group; :obj:`prompts`:
    see :func:`real_items`; :obj:`settings`: the generator's sampling, whose
    latent smoothing and planting the reconstruction and retrieval rows share;
    :obj:`probe_seeds`: seeds of every per-skeleton probe prompt, by
    default :data:`PROBE_SEEDS`, 2 when :obj:`quick`; :obj:`bandai_val`: with
    validation prompts, Bandai's validation takes too, scored by an evaluator
    trained as the test table's, see :func:`bandai_val_items`; :obj:`folder`:
    a user's captioned folders, whose held-out windows are the only test
    prompts, the evaluator learning from the zoo's training clips and the
    folders' training split, see :func:`folder_items`; :obj:`pool_size`:
    R-precision's)."""
    settings = settings or GenerationSettings()
    probe_seeds = probe_seeds or (2 if quick else PROBE_SEEDS)
    start = time.perf_counter()
    encode = cached_encoder()
    if folder is None:
        train, test = real_items(quick, seed, prompts)
        labelled = train
    else:  # a folder's captions are no action labels: the recogniser learns the zoo's
        labelled = zoo_items("train", 128 if quick else 1200, seed, keep=True)
        train, test = labelled + folder.fit, folder.test
    loaded = time.perf_counter()
    steps = steps or (150 if quick else 3000)
    model = train_evaluator(train, encode, steps, seed)
    recogniser = train_recogniser(labelled, steps, seed)
    module = None
    if ckpt:
        module = load_generator(ckpt)
    autoencoder = None
    if reference:
        from satagraph.experiment.train import load_module
        autoencoder = load_module(reference).eval()
    scoring = [(test, train, model, recogniser)]
    if bandai_val and prompts == "val" and MANIFEST.is_file():
        file_train, val = bandai_val_items(train)
        scoring.append((val, file_train, train_evaluator(file_train, encode, steps, seed),
                        train_recogniser(file_train, steps, seed)))
        test = test + val
    rows = []
    for items_of, train_of, model_of, recogniser_of in scoring:
        for name in dict.fromkeys(it.group for it in items_of):
            items = [it for it in items_of if it.group == name]
            extra = {}
            if autoencoder is not None:
                extra[f"reconstruction ({reference})"] = [autoencoded_items(autoencoder, items)]
            if module is not None:
                extra["reconstruction (SATA-RVQ)"] = [reconstructed_items(module, items,
                                                                          settings)]
                extra["generator (GT length)"] = generated_items(module, items, gen_seeds,
                                                                 settings)
            rows += group_rows(name, items, train_of, model_of, recogniser_of, encode,
                               reps or (3 if quick else 20), extra, seed, module, settings,
                               pool_size)
    if module is not None:
        targets = skeleton_targets(test, quick or prompts != "test" or folder is not None)
        run_extra = skeleton_probes(module, targets, probe_seeds, settings=settings)
    else:
        run_extra = []
    facts = {"train_items": len(train), "test_items": len(test), "evaluator_steps": steps,
             "seed": seed, "pool_size": pool_size, "ckpt": ckpt, "reference": reference,
             "quick": quick, "prompts": prompts, "bandai_val": bandai_val,
             "probe_seeds": probe_seeds,
             "settings": vars(settings),
             "seconds_data": round(loaded - start, 1),
             "seconds_total": round(time.perf_counter() - start, 1)}
    if folder is not None:
        facts.update(folder.facts)
    return rows, {"facts": facts, "model": model, "recogniser": recogniser,
                  "skeletons": run_extra}


def data_line(facts: Dict[str, object]) -> str:
    """What a ``--data`` table scored, in words: the folders, split, files
    and windows, what the evaluator learnt from and the pool size."""
    zoo = facts["train_items"] - facts["fit_windows"]
    return (f"Scored on {', '.join(facts['data'])}, split {facts['split']!r}: "
            f"{facts['test_items']} captioned windows of at most {facts['window']} frames "
            f"from {facts['test_files']} files ({facts['test_uncaptioned']} more without a "
            f"caption left out); the evaluator learnt from {zoo} zoo training clips and "
            f"{facts['fit_windows']} windows of {facts['fit_files']} captioned files of the "
            f"'train' split; R@1-3 in pools of {facts['pool_size']}; no action accuracy "
            "(a folder's captions are no action labels).\n\n")


def sampling(args: argparse.Namespace) -> Optional[GenerationSettings]:
    """The generator's sampling settings of the command line (``None``:
    all defaults)."""
    given = {k: getattr(args, k) for k in ("decoding_steps", "guidance", "residual_guidance",
                                           "temperature",
                                           "topk_ratio", "residual_temperature", "layers",
                                           "smooth", "output_smooth", "root_smooth", "plant",
                                           "choice_temperature",
                                           "spread", "rest", "residual_window", "guide",
                                           "draw_guidance", "residual_guide", "rerank",
                                           "carriage")
             if getattr(args, k, None) is not None}
    if "decoding_steps" in given:
        given["steps"] = given.pop("decoding_steps")
    return replace(GenerationSettings(), **given) if given else None


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ckpt", default=None, help="a t2m checkpoint (generator + RVQ)")
    parser.add_argument("--quick", action="store_true", help="zoo only, seconds")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--steps", type=int, default=None, help="evaluator training steps")
    parser.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    parser.add_argument("--save", default=str(ROOT / "runs" / "t2m_evaluator"),
                        help="folder of the trained evaluator")
    parser.add_argument("--prompts", choices=("test", "val"), default="test",
                        help="val: the zoo's validation seeds only (choose sampling settings "
                             "there, report test)")
    parser.add_argument("--bandai-val", action="store_true",
                        help="with --prompts val: Bandai's validation takes too (a real "
                             "human rig, never trained on), scored by an evaluator trained "
                             "as the test table's; the zoo rows are unchanged")
    parser.add_argument("--guidance", type=float, default=None,
                        help="masked transformer guidance (default: generate's)")
    parser.add_argument("--decoding-steps", type=int, default=None,
                        help="iterative decoding steps (default: generate's, 10)")
    parser.add_argument("--residual-guidance", type=float, default=None)
    parser.add_argument("--guide", choices=GUIDES, default=None,
                        help="how guidance enters the masked transformer's draws "
                        "(GenerationSettings.guide)")
    parser.add_argument("--draw-guidance", type=float, default=None,
                        help="with --guide candidates: GenerationSettings.draw_guidance")
    parser.add_argument("--residual-guide", choices=GUIDES, default=None,
                        help="the residual transformer's (GenerationSettings.residual_guide)")
    parser.add_argument("--residual-window", type=float, default=None,
                        help="seconds of the windows the residual layers are filled in "
                        "(0: whole clips; default: generate's)")
    parser.add_argument("--rerank", type=int, default=None,
                        help="layer-0 draws per prompt, the one the text explains best "
                             "kept (GenerationSettings.rerank; default: generate's, "
                             f"{GenerationSettings.rerank})")
    parser.add_argument("--carriage", choices=CARRIAGE_MODES, default=None,
                        help="whether the per-skeleton probes' motions are carried as their "
                             "characters (GenerationSettings.carriage; default: generate's, "
                             f"{GenerationSettings.carriage}); the scored rows never are")
    parser.add_argument("--temperature", type=float, default=None)
    parser.add_argument("--topk-ratio", type=float, default=None)
    parser.add_argument("--residual-temperature", type=float, default=None)
    parser.add_argument("--choice-temperature", type=float, default=None,
                        help="Gumbel noise on which tokens iterative decoding keeps "
                        "(MaskGIT: 4.5; default 0)")
    parser.add_argument("--spread", type=float, default=None,
                        help="keep each decoding step's tokens this share of their mean "
                        "gap apart (default 0: by confidence alone)")
    parser.add_argument("--rest", choices=REST_MODES, default=None,
                        help="the rest pose a rig is shown to the generator in (default: "
                        "generate's, auto)")
    parser.add_argument("--layers", type=int, default=None,
                        help="RVQ layers to decode (default: all)")
    parser.add_argument("--smooth", type=float, default=None,
                        help="latent smoothing in frames (default: generate's)")
    parser.add_argument("--output-smooth", type=float, default=None,
                        help="smoothing of the decoded rotations and root in frames "
                             "(default: generate's)")
    parser.add_argument("--root-smooth", type=float, default=None,
                        help="smoothing of the decoded root features in frames "
                             f"(default: generate's, {GenerationSettings.root_smooth:g})")
    parser.add_argument("--plant", action=argparse.BooleanOptionalAction, default=None,
                        help="plant the feet of decoded motion (default: generate's)")
    parser.add_argument("--probe-seeds", type=int, default=None,
                        help=f"seeds of every per-skeleton probe prompt (default {PROBE_SEEDS}, "
                             "2 with --quick)")
    parser.add_argument("--data", action="append", default=None, metavar="PATH",
                        help="score your own captioned BVH folder (or manifest; repeat for "
                        "several) instead of the project's data: its --split windows are the "
                        "test prompts, its 'train' split joins the zoo's training clips the "
                        "evaluator learns from (split as satagraph train --data splits it)")
    parser.add_argument("--split", choices=("val", "test"), default="test",
                        help="with --data, the held-out split scored (default: test)")
    parser.add_argument("--pool-size", type=int, default=POOL_SIZE,
                        help=f"texts per R-precision pool (default {POOL_SIZE}; at least 4; "
                        "a held-out split needs as many captioned windows)")
    parser.add_argument("--reference", default=None, metavar="AUTOENCODER",
                        help="also a row of test motion through this autoencoder on its own "
                             "rig (builtin, a checkpoint or weights file): the ceiling of "
                             "an RVQ started from it")
    args = parser.parse_args(argv)
    if args.bandai_val and args.prompts != "val":
        parser.error("--bandai-val goes with --prompts val")
    if args.data and (args.prompts != "test" or args.bandai_val):
        parser.error("--data scores its own --split; --prompts val and --bandai-val are the "
                     "project's")
    if args.pool_size < 4:
        parser.error(f"--pool-size must be at least 4 (R@3 in a smaller pool says nothing), "
                     f"got {args.pool_size}")
    if not (args.quick or args.data) and not MANIFEST.is_file():
        parser.error(f"{MANIFEST.parent}: no manifest.tsv there: the real files' groups and "
                     "probes need ../shared/data (--quick scores the zoo alone)")
    torch.set_num_threads(1)
    warnings.simplefilter("ignore")
    try:
        folder = folder_items(args.data, args.split, args.pool_size) if args.data else None
    except (OSError, ValueError) as err:
        parser.error(str(err))
    rows, run = evaluate(args.quick, args.ckpt, args.seed, args.steps,
                         reference=args.reference, prompts=args.prompts,
                         settings=sampling(args), probe_seeds=args.probe_seeds,
                         bandai_val=args.bandai_val, folder=folder, pool_size=args.pool_size)
    name = (("t2m_quick" if args.quick else "t2m") + ("_val" if args.prompts == "val" else "")
            + ("_data" if args.data else ""))
    command = "python benchmarks/t2m.py " + " ".join(argv if argv is not None else sys.argv[1:])
    save = Path(args.save)
    save.mkdir(parents=True, exist_ok=True)
    torch.save({"state_dict": run["model"].state_dict(),
                "recogniser": run["recogniser"].state_dict(),
                "labels": run["recogniser"].labels, "command": command,
                "facts": run["facts"]}, save / f"{name}_evaluator.pt")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    text = (f"# Text-to-motion evaluation\n\n`{command}`\n\n{json.dumps(run['facts'])}\n\n"
            + (data_line(run["facts"]) if args.data else "") + f"{table(rows)}\n")
    text += action_table(rows)
    if run["skeletons"]:
        text += ("\nGenerator probes per skeleton (4 s, prompts of bandai's wording):\n\n"
                 "| skeleton | subject | probes |\n|---|---|---|\n" + "\n".join(
                     f"| {r['skeleton']} | {r['subject']} | {probe_cell(r['probes'])} |"
                     for r in run["skeletons"]) + "\n")
    atomic_write_text(out / f"{name}.md", text)
    atomic_write_text(out / f"{name}.json", json.dumps({"facts": run["facts"], "rows": rows,
                                                  "skeletons": run["skeletons"]},
                                                 indent=1, default=str))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
