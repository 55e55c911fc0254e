r"""Text-to-motion on any skeleton (issue 19): MoMask's masked and residual
transformers over the codes of a frozen SATA-RVQ, a skeleton embedding and
a length model, trained together by one LightningModule.

Every batch is a :class:`~satagraph.data.FrameBatch` of captioned windows
(:mod:`satagraph.data.captioned`); the frozen autoencoder computes the
codes of each window on the fly (so augmentation stays free), the text
encoder the caption embeddings. A training batch may instead be a
:class:`~satagraph.data.code_bank.CodeBatch` of windows coded once
(``data.code_bank``: on two CPU cores a step of 16 windows of 120 frames
then skips the 2.2 s of drawing and coding of its 2.4 s; augmentation is
fixed when the bank is made). The losses:

- ``masked``: masked-token cross-entropy of the layer-0 codes
  (:class:`~satagraph.nn.generators.MaskedTransformer`);
- ``residual``: cross-entropy of one residual layer per window
  (:class:`~satagraph.nn.generators.ResidualTransformer`);
- ``length``: duration cross-entropy
  (:class:`~satagraph.nn.generators.LengthModel`).

Classifier-free guidance drops the text token only; the skeleton token is
never dropped. The checkpoint holds the autoencoder (its hyperparameters and
weights: generation needs no other file) and the text encoder's id and
width (:func:`~satagraph.semantics.text_encoder_state`), checked when
it is loaded. Validation draws its masks from a generator seeded by the
batch index, so ``val_loss`` (what checkpoint selection monitors) is
comparable across epochs.

A config (``module: t2m``, see ``experiments/t2m_tiny.yaml``)::

    module: t2m
    model:
      autoencoder: runs/t2m_rvq_tiny/checkpoints/last.ckpt
      text_encoder: offline
      skeleton: {hidden_channels: 64, out_channels: 64, num_layers: 2}
      masked: {hidden_channels: 64, num_layers: 2, mask_floor: 0.3}
      residual: {hidden_channels: 64, num_layers: 2}
      length: {hidden_channels: 64, max_seconds: 4.0}
"""
from __future__ import annotations

import copy
import math
import os
from typing import Any, Dict, List, Optional, Sequence, Tuple

import lightning as L
import torch
from torch import Tensor, nn

from satagraph.data.datamodule import semantic_embedder
from satagraph.semantics import build_text_encoder
from satagraph.semantics.factory import check_text_encoder_state, text_encoder_state
from satagraph.data.captioned import batch_censored, batch_seconds, batch_texts
from satagraph.data.code_bank import CodeBank, CodeBatch, autoencoder_fingerprint
from satagraph.lightning.per_dataset import PerDatasetFigures, dataset_of, log_per_dataset
from satagraph.lightning.frozen import freeze, keep_frozen, named_parts
from satagraph.io.checkpoint import CheckpointError
from satagraph.io.weights import BUILTIN, is_builtin, load_weights_or_checkpoint
from satagraph.pipelines.inference import default_windows, window_codes
from satagraph.pipelines.prompt_reading import VOCABULARY_KEY, words_of
from satagraph.nn.generators import (LengthModel, MaskedLoss, MaskedTransformer,
                                     ResidualTransformer, SkeletonEmbedding, merge_codes,
                                     parents_to_edge_index, skeleton_graph, split_codes)

#: Loss weights of the three models.
DEFAULT_LOSS: Dict[str, float] = {"masked": 1.0, "residual": 1.0, "length": 0.1}
#: AdamW with a linear warm-up over ``warmup_steps``, then constant, or,
#: with ``decay_steps`` > 0, a cosine from ``lr`` down to ``floor * lr``
#: over that many steps after the warm-up (gradient clipping:
#: ``optim.grad_clip`` of the config schema); ``frozen``: the parts not
#: trained (:meth:`TextToMotionModule.frozen_parts`).
DEFAULT_OPTIM: Dict[str, Any] = {"lr": 2e-4, "weight_decay": 1e-5, "warmup_steps": 200,
                                 "decay_steps": 0, "floor": 0.1, "frozen": ()}
#: The parts of a generator ``optim.frozen`` may name.
GENERATOR_PARTS = ("skeleton", "masked", "residual", "length")

#: The kind of built-in weights a text-to-motion module is
#: (:data:`~satagraph.io.weights.BUILTIN_FILES`).
BUILTIN_KIND = "text-to-motion"
#: Checkpoint key of the text encoder's id and width.
TEXT_ENCODER_KEY = "text_encoder"


def warmup_cosine(step: int, warmup_steps: int, decay_steps: int, floor: float) -> float:
    r"""The generator's schedule: a linear warm-up over :obj:`warmup_steps`,
    then a cosine from 1 to :obj:`floor` over :obj:`decay_steps` (constant 1
    when it is 0), then :obj:`floor`."""
    warmup = max(int(warmup_steps), 1)
    if step < warmup:
        return (step + 1) / warmup
    if decay_steps <= 0:
        return 1.0
    t = min(1.0, (step - warmup) / float(decay_steps))
    return floor + (1.0 - floor) * 0.5 * (1.0 + math.cos(math.pi * t))


def load_autoencoder(spec: Any) -> Tuple[nn.Module, Dict[str, Any]]:
    """The frozen autoencoder of ``model.autoencoder``: a checkpoint path
    (loaded with its weights), ``"builtin"`` (the built-in generator's own,
    :func:`builtin_autoencoder`) or the stored ``{"checkpoint", "hparams"}``
    of a trained generator (built empty: the generator's own weights fill
    it). Returns the module and the stored form."""
    from satagraph.experiment.train import load_module, module_class
    weights = None
    if isinstance(spec, str) and is_builtin(spec, BUILTIN_KIND):
        spec, weights = builtin_autoencoder()
    if isinstance(spec, str):
        if not os.path.isfile(spec):
            raise CheckpointError(f"{spec}: no such autoencoder checkpoint (model.autoencoder;"
                                  " train one with `satagraph train t2m_rvq_tiny`)")
        module = load_module(spec)
        hparams = {k: copy.deepcopy(module.hparams[k])
                   for k in ("model", "loss", "optim", "fps", "meta")}
        stored = {"checkpoint": spec, "hparams": hparams}
    elif isinstance(spec, dict) and "hparams" in spec:
        hparams = spec["hparams"]
        module = module_class(hparams["meta"].get("module", "rvq"))(**hparams)
        stored = spec
    else:
        raise ValueError("model.autoencoder: a SATA-RVQ checkpoint path (or builtin) is "
                         "needed")
    if weights is not None:
        module.load_state_dict(weights)
    if not hasattr(module, "codes"):
        raise CheckpointError(f"{stored['checkpoint']}: a {module.meta.get('module')!r} "
                              "model has no codes: text-to-motion needs a SATA-RVQ "
                              "(module: rvq)")
    module.requires_grad_(False)
    return module.eval(), stored


def builtin_autoencoder() -> Tuple[Dict[str, Any], Dict[str, Tensor]]:
    """The SATA-RVQ the built-in generator was trained over, from the
    generator's own weights file (``model.autoencoder: builtin``): a
    fine-tune of the built-in generator (``--init-from builtin``) then
    reads the codes its weights learnt. Returns its stored form
    (``checkpoint`` is ``"builtin"``), which :func:`load_autoencoder`
    builds, and its weights."""
    payload = load_weights_or_checkpoint(BUILTIN, require=("state_dict", "hyper_parameters"),
                                         kind=BUILTIN_KIND)
    stored = copy.deepcopy(payload["hyper_parameters"]["model"]["autoencoder"])
    stored["checkpoint"] = BUILTIN
    prefix = "autoencoder."
    return stored, {k[len(prefix):]: v for k, v in payload["state_dict"].items()
                    if k.startswith(prefix)}


def check_shared(own: nn.Module, theirs: Dict[str, Tensor], prefix: str, ckpt: str,
                 why: str) -> None:
    """Refuse to swap the part of :obj:`own` below :obj:`prefix` for that of
    :obj:`theirs` (a state dict) unless every other weight is the same (in
    half precision or not): only a part fine-tuned with the rest frozen
    fits the rest.

    Raises:
        CheckpointError: Another weight differs (one line naming
            :obj:`ckpt`, the first such weight and :obj:`why`).
    """
    differ = [k for k, v in own.state_dict().items()
              if not k.startswith(prefix) and not _same_weights(theirs.get(k), v)]
    if differ:
        raise CheckpointError(f"{ckpt}: {differ[0]} (and {len(differ) - 1} more) differ "
                              f"from this model's: {why}")


def _same_weights(other: Optional[Tensor], own: Tensor) -> bool:
    """Whether :obj:`other` is :obj:`own`, or rounds to it in half precision
    (a generator loaded from a ``--half`` weights file)."""
    if other is None or other.shape != own.shape:
        return False
    other = other.to(own.device)
    return torch.equal(other.to(own.dtype), own) or (
        other.is_floating_point() and torch.equal(other.half().to(own.dtype), own))


class TextToMotionModule(PerDatasetFigures, L.LightningModule):
    r"""Masked + residual transformers, skeleton embedding and length model
    over a frozen SATA-RVQ's codes (see the module docstring).

    Args:
        model (dict): ``autoencoder`` (checkpoint path), ``text_encoder``
            (spec, see :func:`~satagraph.semantics.build_text_encoder`),
            and the keyword arguments of ``skeleton``
            (:class:`~satagraph.nn.generators.SkeletonEmbedding`),
            ``masked``, ``residual`` and ``length``.
        loss (dict, optional): Weights of :data:`DEFAULT_LOSS`.
        optim (dict, optional): Keys of :data:`DEFAULT_OPTIM`.
        fps (float): Frame rate of the features.
        meta (dict, optional): ``module``, ``semantic_encoder`` (must be the
            autoencoder's), ``window``, ``data``.
    """

    #: Weights ``--init-from`` leaves as built (:func:`~satagraph.experiment.train.init_weights`):
    #: the frozen autoencoder is the one ``model.autoencoder`` names.
    init_keeps = ("autoencoder.",)

    #: Which built-in weights ``--init-from builtin`` names.
    builtin_kind = BUILTIN_KIND

    def __init__(self, model: Dict[str, Any], loss: Optional[Dict[str, float]] = None,
                 optim: Optional[Dict[str, float]] = None, fps: float = 30.0,
                 meta: Optional[Dict[str, Any]] = None) -> None:
        super().__init__()
        self.save_hyperparameters()
        model = dict(model)
        self.autoencoder, model["autoencoder"] = load_autoencoder(model.get("autoencoder"))
        self.hparams["model"] = model  # the checkpoint rebuilds it without the file
        self.fps, self.meta = float(fps), dict(meta or {})
        self.loss_weights = dict(DEFAULT_LOSS, **(loss or {}))
        self.optim = dict(DEFAULT_OPTIM, **(optim or {}))
        self.text_encoder = build_text_encoder(model.get("text_encoder", "offline"))
        # also in the hyperparameters, which `export-weights` keeps: the
        # record of training, never overwritten by a later load
        self.meta.setdefault(TEXT_ENCODER_KEY, text_encoder_state(self.text_encoder))
        self.hparams["meta"] = self.meta
        self._caption_words = set(self.meta.get(VOCABULARY_KEY) or ())
        self._check_semantic_encoder()
        self._check_facing()
        self.build(model)
        freeze(self.frozen_parts())

    # ------------------------------------------------------------ build
    def _check_semantic_encoder(self) -> None:
        """The data's semantic encoder must be the autoencoder's."""
        own = self.autoencoder.meta.get("semantic_encoder", "offline")
        self.meta.setdefault("semantic_encoder", own)
        if self.meta["semantic_encoder"] != own:
            raise ValueError(f"data.semantic_encoder {self.meta['semantic_encoder']!r} is not "
                             f"the autoencoder's ({own!r})")

    def _check_facing(self) -> None:
        """The data's facing frame must be the autoencoder's
        (``data.preprocessing.facing_smooth``): its codes of root features
        turned another way would be codes of other motion. Skipped where
        either side does not record its data (older checkpoints)."""
        from satagraph.data.dataset import data_facing_smooth
        ours, theirs = self.meta.get("data"), self.autoencoder.meta.get("data")
        if not isinstance(ours, dict) or not isinstance(theirs, dict):
            return
        want, have = data_facing_smooth(theirs), data_facing_smooth(ours)
        if want != have:
            raise ValueError(f"data.preprocessing.facing_smooth={have:g} is not the autoencoder's "
                             f"({want:g}); set data.preprocessing.facing_smooth={want:g}")

    def build(self, model: Dict[str, Any]) -> None:
        """The skeleton embedding, the two transformers and the length model."""
        ae = self.autoencoder
        bottleneck = ae.model.bottleneck
        num_q, num_codes = int(bottleneck.rvq.num_quantizers), int(bottleneck.codebook_size)
        static = int(ae.normalizer.static_mean.numel())
        semantic = int(ae.hparams["model"].get("semantic_channels") or 0)
        skel = dict(model.get("skeleton") or {})
        self.skeleton = SkeletonEmbedding(static + semantic, **skel)
        text, width = int(self.text_encoder.out_channels), self.skeleton.lin.out_features
        self.masked = MaskedTransformer(num_codes, text, width, **(model.get("masked") or {}))
        self.residual = ResidualTransformer(num_codes, num_q, text, width,
                                            **(model.get("residual") or {}))
        self.length = LengthModel(text, width, **(model.get("length") or {}))

    def frozen_parts(self) -> List[nn.Module]:
        """The parts ``optim.frozen`` names (:data:`GENERATOR_PARTS`;
        :func:`~satagraph.lightning.frozen.named_parts`), e.g. all but
        ``length`` to teach the length model alone; a part is frozen with
        its loss still computed unless its weight is 0 (``loss``)."""
        return named_parts(self, self.optim["frozen"], GENERATOR_PARTS)

    def train(self, mode: bool = True) -> "TextToMotionModule":
        """Train mode for the generators; the autoencoder and the frozen
        parts stay in eval."""
        super().train(mode)
        self.autoencoder.eval()
        keep_frozen(self.frozen_parts())
        return self

    @torch.no_grad()
    def swap_decoder(self, ckpt: str) -> None:
        """Decode with the decoder of :obj:`ckpt`, a SATA-RVQ fine-tuned from
        this generator's autoencoder with its encoder and codebooks frozen
        (``optim.frozen``): the codes keep their meaning, so the generator
        needs no retraining. The decoder comes with the latent smoothing it
        was trained under (SATA's ``latent_smooth``).

        Raises:
            CheckpointError: :obj:`ckpt`'s normaliser, encoder or codebooks
                are not the generator's (stored in half precision or not).
        """
        from satagraph.experiment.train import load_module
        module = load_module(ckpt)
        theirs = module.state_dict()
        check_shared(self.autoencoder, theirs, "model.decoder.", ckpt,
                     "only a decoder fine-tuned under its frozen encoder and codebooks "
                     "(optim.frozen) keeps the codes' meaning")
        self.autoencoder.load_state_dict(theirs)
        stored = self.hparams["model"]["autoencoder"]
        stored["decoder"] = ckpt
        smooth = float(getattr(module.model, "latent_smooth", 0.0))
        self.autoencoder.model.latent_smooth = stored["hparams"]["model"]["latent_smooth"] = smooth

    @torch.no_grad()
    def swap_length(self, ckpt: str) -> None:
        """Draw durations with the length model of :obj:`ckpt`, a generator
        fine-tuned from this one with every other part frozen
        (``optim.frozen=[skeleton,masked,residual]``, its autoencoder this
        one's); the length model's shape may differ (other bins).

        Raises:
            CheckpointError: Any other weight of :obj:`ckpt` is not this
                generator's (stored in half precision or not).
        """
        from satagraph.experiment.train import load_module
        theirs = load_module(ckpt)
        check_shared(self, theirs.state_dict(), "length.", ckpt,
                     "only a length model trained with every other part frozen "
                     "(optim.frozen) fits the rest")
        self.length = theirs.length.to(self.device)
        self.hparams["model"]["length"] = copy.deepcopy(theirs.hparams["model"].get("length"))

    # ------------------------------------------------------------ inputs
    @property
    def num_quantizers(self) -> int:
        return self.residual.num_quantizers

    @torch.no_grad()
    def batch_codes(self, batch) -> Tuple[Tensor, Tensor]:
        r"""Codes of every window by the frozen autoencoder, in its own
        training windows where the data's are longer
        (:func:`~satagraph.pipelines.inference.window_codes`), as
        :func:`~satagraph.pipelines.generate.decode_on` decodes them.

        Shapes:
            - **output**: codes :math:`(B, T_{max}, Q)` (``-1`` after each
              window) and frames :math:`(B,)`
        """
        lengths = batch.clip_num_frames
        if batch.max_time <= default_windows(self.autoencoder)[0]:
            codes = self.autoencoder.codes(batch)
        else:
            codes = torch.cat(window_codes(self.autoencoder, batch.to_clip_list()))
        return split_codes(codes, lengths.to(codes.device)), lengths

    @torch.no_grad()
    def bank_batch(self, batch, fingerprint: Optional[str] = None) -> CodeBank:
        """The windows of a :class:`~satagraph.data.FrameBatch` as a
        :class:`~satagraph.data.code_bank.CodeBank`: their codes
        (:meth:`batch_codes`), skeletons (as :meth:`skeleton_embedding`
        reads them), captions and durations (:obj:`fingerprint`: the
        autoencoder's, where the caller has it)."""
        codes, lengths = self.batch_codes(batch)
        graph = skeleton_graph(self.autoencoder.normalize_batch(batch))
        fingerprint = fingerprint or autoencoder_fingerprint(self.autoencoder)
        return CodeBank.of_batch(merge_codes(codes, lengths), lengths, graph.x,
                                 batch.stream_parent, graph.batch, batch_seconds(batch),
                                 batch_texts(batch), fingerprint, batch_censored(batch))

    def skeleton_embedding(self, batch) -> Tensor:
        r""":math:`f_{skel}` of every clip's skeleton (static features
        normalised as the autoencoder's).

        Shapes:
            - **output**: :math:`(B, D_s)`
        """
        norm = self.autoencoder.normalize_batch(batch)
        graph = skeleton_graph(norm)
        return self.skeleton(graph.x, graph.edge_index, graph.batch, graph.root)

    @torch.no_grad()
    def encode_text(self, texts: List[str]) -> Tensor:
        r"""Text embeddings on the module's device.

        Shapes:
            - **output**: :math:`(B, D_{text})`
        """
        return self.text_encoder.encode(list(texts)).float().to(self.device)

    # ------------------------------------------------------------ steps
    def batch_inputs(self, batch, coded: bool = True) -> Tuple:
        r"""What the losses read of a :class:`~satagraph.data.FrameBatch` or
        a banked :class:`~satagraph.data.code_bank.CodeBatch`: per-window
        codes and frames (``None`` for a frame batch when not
        :obj:`coded`), captions, skeleton embeddings, durations and their
        censoring flags.

        Shapes:
            - **codes**: :math:`(B, T_{max}, Q)`, **frames**, **seconds**,
              **censored**: :math:`(B,)`, **skel**: :math:`(B, D_s)`
        """
        if isinstance(batch, CodeBatch):
            edge_index, root = parents_to_edge_index(batch.parent)
            skel = self.skeleton(batch.x, edge_index, batch.node_clip, root)
            return (split_codes(batch.codes, batch.num_frames), batch.num_frames, batch.texts,
                    skel, batch.seconds, batch.censored)
        codes, lengths = self.batch_codes(batch) if coded else (None, None)
        return (codes, lengths, batch_texts(batch), self.skeleton_embedding(batch),
                batch_seconds(batch), batch_censored(batch))

    def compute_losses(self, batch, generator: Optional[torch.Generator] = None,
                       per_dataset: Optional[str] = None) -> Dict[str, Tensor]:
        """The three losses, their weighted sum (``loss``) and accuracies;
        with :obj:`per_dataset` (a stage name), also logs the masked loss
        and accuracy per dataset (:mod:`~satagraph.lightning.per_dataset`).
        A transformer whose loss weight is 0 is not run, and where neither
        runs the windows are not coded (training the length model alone
        costs no autoencoder pass)."""
        run = {k: self.loss_weights[k] > 0 for k in ("masked", "residual")}
        codes, lengths, texts, skel, seconds, censored = self.batch_inputs(
            batch, any(run.values()))
        if self.training:
            self.note_words(texts)
        text = self.encode_text(texts)
        out, masked = {}, None
        if run["masked"]:
            masked = self.masked.loss(codes, text, skel, lengths, generator)
            out.update(masked=masked.loss, masked_acc=masked.accuracy)
        if run["residual"]:
            residual = self.residual.loss(codes, text, skel, lengths, generator)
            out.update(residual=residual.loss, residual_acc=residual.accuracy)
        device = skel.device
        out["length"] = self.length.loss(seconds.to(device), text, skel, generator,
                                         None if censored is None else censored.to(device))
        out["loss"] = sum(self.loss_weights[k] * out[k] for k in DEFAULT_LOSS if k in out)
        if per_dataset and masked is not None and not isinstance(batch, CodeBatch):
            log_per_dataset(self, per_dataset, self.masked_per_clip(masked),
                            dataset_of(batch.meta), masked.corruption.mask.sum(-1))
        return out

    @torch.no_grad()
    def masked_per_clip(self, masked: MaskedLoss) -> Dict[str, Tensor]:
        r"""The masked loss and accuracy of every clip, over its masked
        tokens (their token-weighted mean is the batch's).

        Shapes:
            - every value: :math:`(B,)`
        """
        mask = masked.corruption.mask
        targets = masked.targets.masked_fill(~mask, 0)
        token = torch.nn.functional.cross_entropy(
            masked.logits.transpose(1, 2), targets, reduction="none",
            label_smoothing=self.masked.label_smoothing)
        hit = (masked.logits.argmax(-1) == targets).float()
        count = mask.sum(-1).clamp(min=1)
        return {name: (value * mask).sum(-1) / count
                for name, value in (("masked", token), ("masked_acc", hit))}

    def note_words(self, texts: Sequence[str]) -> None:
        """Add the words of training captions to the record of the words
        the model knows (``meta["caption_words"]``, kept sorted in
        checkpoints and weights files; :func:`~satagraph.pipelines.prompt_reading.read_prompt`
        reads prompts in them)."""
        new = words_of(texts) - self._caption_words
        if new:
            self._caption_words |= new
            self.meta[VOCABULARY_KEY] = sorted(self._caption_words)

    def init_meta(self, meta: Dict[str, Any]) -> None:
        """``--init-from``: a fine-tune knows the words its weights learnt
        as well as its own captions'."""
        self.note_words(meta.get(VOCABULARY_KEY) or ())

    def _step(self, batch, stage: str, generator: Optional[torch.Generator] = None) -> Tensor:
        losses = self.compute_losses(batch, generator, None if stage == "train" else stage)
        size = len(batch) if isinstance(batch, CodeBatch) else len(batch.meta)
        terms = {f"{stage}/{k}": v.detach() for k, v in losses.items() if k != "loss"}
        self.log_dict(terms,  # the total once: {stage}_loss
                      batch_size=size, on_epoch=True, on_step=stage == "train",
                      sync_dist=stage != "train")
        self.log(f"{stage}_loss", losses["loss"].detach(), batch_size=size, prog_bar=True,
                 on_epoch=True, sync_dist=stage != "train")
        return losses["loss"]

    def on_fit_start(self) -> None:
        """A code bank (``data.code_bank``) must hold this autoencoder's codes."""
        bank = getattr(getattr(self.trainer, "datamodule", None), "bank", None)
        if bank is not None:
            bank.check_autoencoder(self.autoencoder, ", ".join(self.trainer.datamodule.code_bank))

    def training_step(self, batch, batch_idx: int) -> Tensor:
        return self._step(batch, "train")

    def validation_step(self, batch, batch_idx: int) -> Tensor:
        return self._step(batch, "val", torch.Generator().manual_seed(batch_idx))

    def test_step(self, batch, batch_idx: int) -> Tensor:
        return self._step(batch, "test", torch.Generator().manual_seed(batch_idx))

    def configure_optimizers(self):
        params = [p for p in self.parameters() if p.requires_grad]
        opt = torch.optim.AdamW(params, lr=float(self.optim["lr"]),
                                weight_decay=float(self.optim["weight_decay"]))
        args = (int(self.optim["warmup_steps"]), int(self.optim["decay_steps"]),
                float(self.optim["floor"]))
        sched = torch.optim.lr_scheduler.LambdaLR(opt, lambda s: warmup_cosine(s, *args))
        return {"optimizer": opt, "lr_scheduler": {"scheduler": sched, "interval": "step"}}

    # ------------------------------------------------------------ checkpoints
    def on_save_checkpoint(self, checkpoint: Dict[str, Any]) -> None:
        checkpoint[TEXT_ENCODER_KEY] = text_encoder_state(self.text_encoder)

    def on_load_checkpoint(self, checkpoint: Dict[str, Any]) -> None:
        """Refuses a checkpoint without the text encoder record (its own
        key, or ``meta`` of a weights file) or trained with another encoder
        than the one its spec builds now."""
        state = checkpoint.get(TEXT_ENCODER_KEY)
        if state is None:
            meta = (checkpoint.get("hyper_parameters") or {}).get("meta") or {}
            state = meta.get(TEXT_ENCODER_KEY)
        if not isinstance(state, dict):
            raise CheckpointError("not a text-to-motion checkpoint (no text encoder record)")
        check_text_encoder_state(state, self.text_encoder)

    def semantic_fn(self):
        """The autoencoder's semantic embedder (skeleton -> ``[J, D_t]``)."""
        return semantic_embedder(self.meta.get("semantic_encoder", "offline"))


__all__ = ["TextToMotionModule", "load_autoencoder", "DEFAULT_LOSS", "DEFAULT_OPTIM",
           "TEXT_ENCODER_KEY"]
