"""LightningModules for motion autoencoders (SATA-VAE, SATA-RVQ, baselines)."""
from __future__ import annotations

import copy
import warnings
from typing import Any, Dict, List, Optional

import lightning as L
import torch
from torch import Tensor, nn

from satagraph.ops.smoothing import gaussian_smooth
from satagraph.typing import DYNAMIC_LAYOUT
from satagraph.data.normalizer import FeatureNormalizer
from satagraph.metrics import motion_metrics
from satagraph.lightning.per_dataset import PerDatasetFigures, dataset_of, log_per_dataset
from satagraph.lightning.frozen import freeze, keep_frozen, named_parts
from satagraph.ops.motion_batch import batch_global_motion

DEFAULT_OPTIM: Dict[str, Any] = {"lr": 1e-4, "warmup_epochs": 30, "decay": 0.99,
                                 "floor": 0.01, "frozen": ()}
#: The learning rate of :meth:`MotionAutoencoderModule.refine_latent`.
REFINE_LR = 0.05
#: The cross-skeleton loss terms of :meth:`MotionAutoencoderModule.retarget_losses`.
RETARGET_TERMS = ("retarget", "retarget_root", "retarget_carriage")


def lr_factor(epoch: int, warmup_epochs: int, decay: float, floor: float) -> float:
    r"""The SATA schedule: linear warm-up over :obj:`warmup_epochs`, then
    ``decay ** epoch`` (after warm-up), never below :obj:`floor`."""
    if epoch < warmup_epochs:
        return (epoch + 1) / warmup_epochs
    return max(floor, decay ** (epoch - warmup_epochs))


class MotionAutoencoderModule(PerDatasetFigures, L.LightningModule):
    r"""Base LightningModule for topology-agnostic motion autoencoders.

    Subclasses choose the network in :meth:`build_model` and may override
    the documented hooks:

    - :meth:`encode` ``(batch) -> dict`` (``"z"`` and auxiliary terms),
    - :meth:`decode` ``(z, target) -> dict`` of normalised predictions
      ``q [N, 6]``, ``r [G, 4]``, ``c [N, 1]`` (contact logits),
    - :meth:`compute_losses` ``(out, batch) -> dict`` with ``"loss"``,
    - :meth:`configure_optimizers` (Adam, warm-up, exponential decay with
      a floor: :func:`lr_factor`).

    The module owns the semantic encoder it was trained with
    (``meta["semantic_encoder"]``): :meth:`embed` gives a skeleton's
    semantic features, built once per module, for inference, evaluation,
    sweeps and benchmarks alike.

    Batches are :class:`~satagraph.data.FrameBatch` objects with physical
    (unnormalised) features; the module normalises inputs with its
    :attr:`normalizer` (fitted on the training split by the data module and
    stored in the checkpoint) and denormalises predictions before losses and
    metrics.

    Args:
        model (dict): Keyword arguments of the network.
        loss (dict, optional): Loss weights (see :mod:`satagraph.losses`).
        optim (dict, optional): ``lr``, ``warmup_epochs``, ``decay``,
            ``floor`` (``grad_clip`` is the trainer's, see
            :mod:`satagraph.experiment.schema`) and ``frozen``: parts not
            trained (:meth:`frozen_parts`).
        fps (float): Frame rate the module was trained at (what inference
            resamples motion to; :meth:`setup` refuses a data module whose
            ``preprocessing`` says another); losses and metrics use each
            batch's own (:attr:`~satagraph.data.FrameBatch.fps`).
        meta (dict, optional): What inference needs to know about the data
            (``semantic_encoder``, ``window``, ``module``), kept in the
            checkpoint.
    """

    def __init__(self, model: Dict[str, Any], loss: Optional[Dict[str, float]] = None,
                 optim: Optional[Dict[str, float]] = None, fps: float = 30.0,
                 meta: Optional[Dict[str, Any]] = None) -> None:
        super().__init__()
        self.save_hyperparameters()
        self.optim = dict(DEFAULT_OPTIM, **(optim or {}))
        self.fps = fps
        self.meta = dict(meta or {})
        self._name_module()
        self.normalizer = FeatureNormalizer()
        self.model = self.build_model(**model)
        self.criterion = self.build_loss(**(loss or {}))
        freeze(self.frozen_parts())
        rate = int(getattr(self.model, "latent_rate", 1))
        if self._retarget_weight() > 0 and rate != 1:
            raise ValueError(f"loss.retarget needs one latent per frame (decoded onto "
                             f"another skeleton's frames); {type(self.model).__name__} "
                             f"has one per {rate} frames: set loss.retarget, "
                             "loss.retarget_root and loss.retarget_carriage to 0")

    def _name_module(self) -> None:
        """``meta["module"]`` of a module built by hand (a config's build
        names it): the name its class is registered under
        (:func:`~satagraph.experiment.registry.registered_name`), so that
        :func:`~satagraph.experiment.train.load_module` builds its class
        again, a subclass's own arguments included; none where the class is
        registered under no one name."""
        from satagraph.experiment.registry import registered_name
        name = None if "module" in self.meta else registered_name(type(self))
        if name is not None:
            self.meta["module"] = name
            self.hparams["meta"] = self.meta

    # -------------------------------------------------------- semantics
    def embed(self, skeleton, evidence=None) -> Tensor:
        r"""Semantic features of :obj:`skeleton` with the module's encoder
        (:func:`~satagraph.data.datamodule.semantic_embedder` of
        ``meta["semantic_encoder"]``, its text embeddings cached as
        :meth:`set_semantic_cache` says); :math:`(J, 0)` for a module
        trained without semantics. :obj:`evidence` (a
        :class:`~satagraph.semantics.JointEvidence`) lets the rules read
        the body from its motion.

        Shapes:
            - **output**: :math:`(J, D_t)`
        """
        embedder = self.__dict__.get("_embedder")
        if embedder is None:
            from satagraph.data.datamodule import semantic_embedder
            embedder = semantic_embedder(self.meta.get("semantic_encoder", "offline"),
                                         self.__dict__.get("_semantic_cache")) or _no_semantics
            self.__dict__["_embedder"] = embedder
        return embedder(skeleton, evidence=evidence)

    def set_semantic_cache(self, cache_dir: Optional[str]) -> None:
        """Cache folder of :meth:`embed`'s text embeddings (``None``: the
        default cache root); not saved with the module."""
        self.__dict__["_semantic_cache"] = cache_dir
        self.__dict__.pop("_embedder", None)

    def __getstate__(self) -> Dict[str, Any]:
        state = super().__getstate__()
        state.pop("_embedder", None)  # a text encoder: rebuilt after unpickling
        return state

    # ------------------------------------------------------------ hooks
    def build_model(self, **kwargs: Any) -> nn.Module:
        """The network; subclasses override.

        Raises:
            NotImplementedError: A subclass that does not (one line saying
                what to do).
        """
        raise NotImplementedError(
            f"{type(self).__name__} builds no network: MotionAutoencoderModule's subclasses "
            "override build_model(**model_section) (or derive from SATAVAEModule or "
            "SATARVQModule, the built-in 'vae' and 'rvq')")

    def build_loss(self, **weights: float) -> nn.Module:
        """The loss (:attr:`criterion`); weights from the config's ``loss``
        section. :meth:`compute_losses` calls it as ``criterion(out, batch,
        normalizer)`` for a dict of named terms and their weighted sum under
        ``"loss"``, and reads the ``retarget`` and ``retarget_root`` weights
        from its ``weights`` dict, where it has one
        (:class:`~satagraph.losses.MotionLoss`, the default)."""
        from satagraph.losses import MotionLoss
        return MotionLoss(**weights)

    def encode(self, batch) -> Dict[str, Tensor]:
        """Latents of a (normalised) batch: ``{"z": [G, D], ...}``."""
        return self.model.encode(batch)

    def decode(self, z: Tensor, target) -> Dict[str, Tensor]:
        """Normalised predictions on the target skeletons' frame graphs."""
        return self.model.decode(z, target)

    def forward(self, batch, target=None, refine: int = 0) -> Dict[str, Tensor]:
        """Encode :obj:`batch`, decode on :obj:`target` (default: itself).
        Both are physical batches; predictions come back physical. With
        :obj:`refine` steps, the latent is first fitted to :obj:`batch`
        (:meth:`refine_latent`)."""
        source = self.normalize_batch(batch)
        normed = source if target is None else self.normalize_batch(target)
        enc = self.encode(source)
        if refine:
            enc = dict(enc, z=self.refine_latent(enc, source, batch, refine))
        out = dict(enc, **self.decode(enc["z"], normed))
        return self.denormalize_output(out, batch if target is None else target)

    def refine_latent(self, enc: Dict[str, Tensor], source, batch, steps: int,
                      lr: float = REFINE_LR) -> Tensor:
        r"""The encoder's latent fitted to its input: :obj:`steps` Adam
        steps of rate :obj:`lr` on the latent alone (the weights frozen,
        none of their gradients kept) lowering :attr:`criterion`, the
        training loss, of :obj:`batch` decoded from it on its own skeleton.
        The latent then says more of the input than the encoder read from
        it (``experiments/PRETRAIN.md`` section 56: on rigs never trained
        on, the dog's error fell to a fifth); an RVQ's quantised latent is
        no longer made of its codes.

        Args:
            enc (dict): :meth:`encode`'s output for :obj:`source`.
            source: The normalised batch (:meth:`normalize_batch`).
            batch: The same batch, physical (what the loss compares with).
            steps (int): Adam steps.
            lr (float): Their learning rate.

        Returns:
            Tensor: The fitted latent, detached.

        Shapes:
            - **enc["z"]**, **output**: :math:`(G, D)`
        """
        enc = {k: v.detach() if torch.is_tensor(v) else v for k, v in enc.items()}
        z = enc["z"].clone().requires_grad_(True)
        optimizer = torch.optim.Adam([z], lr=lr)
        with torch.enable_grad():
            for _ in range(steps):
                out = self.denormalize_output(dict(enc, z=z, **self.decode(z, source)), batch)
                loss = self.criterion(out, batch, self.normalizer)["loss"]
                (z.grad,) = torch.autograd.grad(loss, [z])
                optimizer.step()
        return z.detach()

    # --------------------------------------------------- normalisation
    def setup(self, stage: str) -> None:
        """Take the data module's fitted normaliser (any data module with a
        ``normalizer``); warn before training with none fitted."""
        dm = getattr(self.trainer, "datamodule", None) if self._trainer else None
        theirs = getattr(dm, "normalizer", None)
        if not bool(self.normalizer.fitted) and theirs is not None:
            self.normalizer.load_state_dict(theirs.state_dict())
        if stage == "fit" and not bool(self.normalizer.fitted):
            warnings.warn(f"{type(self).__name__}: training with an unfitted feature "
                          "normaliser (mean 0, std 1, saved so in the checkpoint): train on a "
                          "MotionDataModule, give your data module a fitted `normalizer`, or "
                          "call module.normalizer.fit(training_features) first", stacklevel=2)
        if dm is not None and hasattr(dm, "pair_partners"):
            # partners for the retarget term are collated with the batch
            dm.pair_partners = self._retarget_weight() > 0
        if dm is not None:
            self._check_semantic_width(dm)
        if dm is not None and stage == "fit":
            self._check_fps(dm)
            self._adopt_data_meta(dm)

    def _adopt_data_meta(self, dm: Any) -> None:
        """``meta["window"]`` and ``meta["semantic_encoder"]`` (what
        inference and :meth:`embed` read) from the data module where the
        module was built without them, in the checkpoint too; refuse ones
        that differ (a hand-built module decoded 64-frame windows and
        embedded joints with the offline encoder whatever it trained on)."""
        theirs = {key: getattr(dm, key) for key in ("window", "semantic_encoder")
                  if hasattr(dm, key)}
        for key, value in theirs.items():
            if key not in self.meta:
                self.meta[key] = value
                self.__dict__.pop("_embedder", None)  # built from the default encoder
            elif self.meta[key] != value:
                raise ValueError(f"the data's {key} is {value!r} (data.{key}) but the "
                                 f"module's meta says {self.meta[key]!r}: build the module "
                                 f"with meta['{key}']={value!r} "
                                 "(build_module(cfg, datamodule) sets it)")
        self.hparams["meta"] = self.meta

    def _check_fps(self, dm: Any) -> None:
        """Refuse data at another frame rate than :attr:`fps`, the rate
        inference resamples motion to (a module built by hand kept the
        default 30 while it trained on 60 fps windows, silently)."""
        from satagraph.data.dataset import DEFAULT_PREPROCESSING
        preprocessing = getattr(dm, "preprocessing", None)
        if not isinstance(preprocessing, dict):
            return
        rate = float(dict(DEFAULT_PREPROCESSING, **preprocessing)["fps"])
        if abs(rate - float(self.fps)) > 1e-6:
            raise ValueError(f"the data's windows are at {rate:g} fps "
                             f"(data.preprocessing.fps) but the module's fps is "
                             f"{float(self.fps):g}, the rate inference resamples motion to: "
                             f"build the module with fps={rate:g} "
                             "(build_module(cfg, datamodule) sets it)")

    def _check_semantic_width(self, dm: Any) -> None:
        """Refuse data whose semantic features the network would not read
        (a module built with ``semantic_channels`` 0 ignored the data's
        256-wide ones, silently) or would read at another width."""
        from satagraph.nn.layers.modulation import SemanticModulation
        layers = [m for m in self.model.modules() if isinstance(m, SemanticModulation)]
        width = _semantic_width(dm)
        if width is None or not layers:
            return
        ours = layers[0].phi_t.in_features if layers[0].phi_t is not None else 0
        if ours == width or (not ours and self.hparams["model"].get("use_text") is False):
            return
        encoder = getattr(dm, "semantic_encoder", None)
        raise ValueError(
            f"the data's semantic features are {width} wide (semantic_encoder "
            f"{encoder!r}) but the model reads {ours or 'none'}: build the module "
            f"with model.semantic_channels={width} (build_module(cfg, datamodule) sets "
            "it from the data), or model.use_text=false to train without them")

    def normalize_batch(self, batch):
        """A shallow copy of :obj:`batch` with normalised features (lengths
        in each clip's heights when the normaliser is body-relative), in the
        module's floating type (a float64 batch is read as float32 by a
        float32 module)."""
        out = copy.copy(batch)
        norm = self.normalizer
        dtype = norm.dynamic_mean.dtype
        out.x = norm.normalize(batch.x, "dynamic", batch.heights("node")).to(dtype)
        out.root = norm.normalize(batch.root, "root", batch.heights("frame"),
                                  batch.legs("frame")).to(dtype)
        out.joint_static = norm.normalize(batch.joint_static, "static",
                                          batch.heights("stream")).to(dtype)
        return out

    def denormalize_output(self, out: Dict[str, Tensor], target) -> Dict[str, Tensor]:
        """Physical predictions on :obj:`target` (the physical batch that
        was decoded onto: its clip heights scale the root lengths); the
        normalised ones stay under ``q_norm`` and ``r_norm``."""
        out = dict(out)
        out["q_norm"], out["r_norm"] = out["q"], out["r"]
        out["q"] = self.normalizer.denormalize(out["q"], "dynamic", DYNAMIC_LAYOUT["q"])
        out["r"] = self.normalizer.denormalize(out["r"], "root",
                                               height=target.heights("frame"),
                                               leg=target.legs("frame"))
        return out

    # ----------------------------------------------------------- steps
    def compute_losses(self, out: Dict[str, Tensor], batch) -> Dict[str, Tensor]:
        """Named loss terms and their weighted sum under ``"loss"``; with a
        weight on any of :data:`RETARGET_TERMS`, also the cross-skeleton
        terms of :meth:`retarget_losses` of ``out["z"]``."""
        losses = self.criterion(out, batch, self.normalizer)
        weights = {k: self._loss_weight(k) for k in RETARGET_TERMS}
        if any(w > 0 for w in weights.values()) and "z" in out:
            terms = self.retarget_losses(out["z"], batch)
            for name, weight in weights.items():
                if weight > 0:
                    # logged every step (zero without a pair), so that every
                    # process of a distributed run logs the same keys
                    losses[name] = out["z"].sum() * 0.0 if terms is None else terms[name]
                    losses["loss"] = losses["loss"] + weight * losses[name]
        return losses

    def _loss_weight(self, name: str) -> float:
        return float(getattr(self.criterion, "weights", {}).get(name, 0.0))

    def _retarget_weight(self) -> float:
        """The largest weight of the cross-skeleton terms (0: none is on)."""
        return max(self._loss_weight(k) for k in RETARGET_TERMS)

    def retarget_loss(self, z: Tensor, batch) -> Optional[Tensor]:
        """The limb term of :meth:`retarget_losses` (``None`` when every
        clip of the batch has the same skeleton)."""
        terms = self.retarget_losses(z, batch)
        return None if terms is None else terms["retarget"]

    def retarget_losses(self, z: Tensor, batch) -> Optional[Dict[str, Tensor]]:
        """Unpaired cross-skeleton terms: every clip's latents :obj:`z`
        decoded onto another skeleton of the batch must move the limb ends
        like the source (``retarget``:
        :func:`~satagraph.losses.limb_velocity_loss`) and carry the root
        like it (``retarget_root``: :func:`~satagraph.losses.root_transfer_loss`),
        and carry each joint as the partner's own clip carries it
        (``retarget_carriage``: :func:`~satagraph.losses.carriage_loss`).
        Partners come with the batch (``batch.pairing``, collated by
        :class:`~satagraph.data.pairing.PartnerCollate`), else are drawn here
        from a generator seeded with the global step
        (:func:`~satagraph.data.pairing.partner_batch`). ``None`` when every
        clip of the batch has the same skeleton."""
        from torch_geometric.utils import scatter
        from satagraph.data.pairing import pairing_to, partner_batch
        from satagraph.losses import (carriage_loss, facing_positions, limb_velocity_loss,
                                      root_transfer_loss)
        pairing = getattr(batch, "pairing", None)
        if pairing is None:
            gen = torch.Generator().manual_seed(int(self.global_step))
            pairing = partner_batch(batch, gen)
        if pairing is None:
            return None
        pairing = pairing_to(pairing, z.device)
        target = self.normalize_batch(pairing.target)
        pred = self.denormalize_output(self.decode(z[pairing.frames], target),
                                       pairing.target)
        pos = facing_positions(pred["q"], pred["r"], pairing.target)
        source_x = batch.x[:, DYNAMIC_LAYOUT["x"]]
        low_source = scatter(source_x[:, 1], batch.batch, 0, batch.num_graphs, "min")
        low_target = scatter(pos[:, 1], pairing.target.batch, 0, pairing.target.num_graphs,
                             "min")
        return {"retarget": limb_velocity_loss(source_x, pos, pairing),
                "retarget_root": root_transfer_loss(
                    batch.root[pairing.frames], pred["r"],
                    batch.heights("frame")[pairing.frames], pairing.target.heights("frame"),
                    low_source[pairing.frames], low_target, batch.legs("frame")[pairing.frames],
                    pairing.target.legs("frame")),
                "retarget_carriage": carriage_loss(pos, source_x, pairing.target, batch,
                                                   pairing.partners)}

    def _step(self, batch, stage: str) -> Tensor:
        out = self(batch)
        losses = self.compute_losses(out, batch)
        size = len(batch.meta)
        terms = {f"{stage}/{k}": v.detach() for k, v in losses.items() if k != "loss"}
        self.log_dict(terms,  # the total once: {stage}_loss
                      batch_size=size, prog_bar=False, on_epoch=True,
                      on_step=stage == "train", sync_dist=stage != "train")
        self.log(f"{stage}_loss", losses["loss"].detach(), batch_size=size,
                 prog_bar=True, on_epoch=True, sync_dist=stage != "train")
        if stage != "train":
            metrics = self.metrics(out, batch)
            self.log_dict({f"{stage}/{k}": v.mean() for k, v in metrics.items()},
                          batch_size=size, on_epoch=True, sync_dist=True)
            log_per_dataset(self, stage, metrics, dataset_of(batch.meta))
        return losses["loss"]

    def training_step(self, batch, batch_idx: int) -> Tensor:
        return self._step(batch, "train")

    def validation_step(self, batch, batch_idx: int) -> Tensor:
        return self._step(batch, "val")

    def test_step(self, batch, batch_idx: int) -> Tensor:
        return self._step(batch, "test")

    @torch.no_grad()
    def metrics(self, out: Dict[str, Tensor], batch) -> Dict[str, Tensor]:
        """Per-clip metrics of a (physical) prediction against the batch: a
        dict of ``[num_clips]`` tensors (a subclass's too), logged as
        ``{stage}/{name}`` (their clip-weighted means) and per dataset."""
        q_true = batch.x[:, DYNAMIC_LAYOUT["q"]]
        local_t, _, pos_t = batch_global_motion(q_true, batch.root, batch)
        local_p, _, pos_p = batch_global_motion(out["q"], out["r"], batch)
        return motion_metrics(local_p, pos_p, local_t, pos_t, batch)

    def frozen_parts(self) -> List[nn.Module]:
        r"""The parts ``optim.frozen`` names (paths below the module, e.g.
        ``model.encoder``, ``model.bottleneck``;
        :func:`~satagraph.lightning.frozen.named_parts`): left out of the
        optimiser and kept in evaluation mode while training, so that a
        frozen quantiser's codebooks do not move either. Fine-tuning a
        decoder under frozen encoder and codebooks keeps a code sequence's
        meaning, so a generator trained over those codes stays valid.

        Raises:
            ValueError: A name that is not a part of the module.
        """
        known = [f"model.{n}" for n, _ in self.model.named_children()]
        return named_parts(self, self.optim["frozen"], known)

    def train(self, mode: bool = True) -> "MotionAutoencoderModule":
        super().train(mode)
        keep_frozen(self.frozen_parts())
        return self

    def configure_optimizers(self):
        params = [p for p in self.parameters() if p.requires_grad]
        opt = torch.optim.Adam(params, lr=self.optim["lr"])
        sched = torch.optim.lr_scheduler.LambdaLR(opt, lambda e: lr_factor(
            e, int(self.optim["warmup_epochs"]), self.optim["decay"], self.optim["floor"]))
        return {"optimizer": opt, "lr_scheduler": {"scheduler": sched, "interval": "epoch"}}


class SATAVAEModule(MotionAutoencoderModule):
    r"""SATA with a 128-D Gaussian bottleneck (paper section 4.1)."""

    def build_model(self, **kwargs: Any) -> nn.Module:
        from satagraph.nn import SATA
        return SATA(**dict({"bottleneck": "vae"}, **kwargs))


class SATARVQModule(MotionAutoencoderModule):
    r"""SATA with a residual vector quantiser (6 x 1024 codes, 256-D)."""

    def build_model(self, **kwargs: Any) -> nn.Module:
        from satagraph.nn import SATA
        return SATA(**dict({"bottleneck": "rvq"}, **kwargs))

    @torch.no_grad()
    def codes(self, batch) -> Tensor:
        """Code indices per frame, ``[G, Q]``, of a physical batch, for
        generators. Evaluation mode only: in training mode quantiser dropout
        leaves ``-1`` codes."""
        if self.training:
            raise RuntimeError("SATARVQModule.codes: call module.eval() first (in "
                               "training mode quantiser dropout leaves -1 codes)")
        return self.encode(self.normalize_batch(batch))["codes"]

    @torch.no_grad()
    def decode_codes(self, codes: Tensor, target, smooth: float = 0.0) -> Dict[str, Tensor]:
        r"""Physical predictions (``q``, ``r``, contact logits ``c``) of
        per-frame codes decoded onto the frame graphs of :obj:`target` (a
        physical :class:`~satagraph.data.FrameBatch` whose frames match the
        codes'), the dequantised latents first smoothed along each clip's
        frames by a Gaussian of :obj:`smooth` frames in all
        (:func:`~satagraph.ops.smoothing.gaussian_smooth`; 0: none). A
        network that smooths its latents itself (SATA's ``latent_smooth``)
        gets only the remainder (Gaussian widths add in squares), never
        less than its own.

        Shapes:
            - **codes**: :math:`(G, Q)`
        """
        own = float(getattr(self.model, "latent_smooth", 0.0))
        rest = max(smooth ** 2 - own ** 2, 0.0) ** 0.5
        z = gaussian_smooth(self.model.bottleneck.decode_codes(codes), target.clip_num_frames,
                            rest)
        return self.denormalize_output(self.decode(z, self.normalize_batch(target)), target)


def _semantic_width(dm: Any) -> Optional[int]:
    """Width of the semantic features a data module's windows carry
    (``None`` before its set-up, or for data without windows)."""
    for ds in (getattr(dm, "datasets", None) or {}).values():
        if len(ds) and hasattr(ds[0], "semantic"):
            return int(ds[0].semantic.shape[-1])
    return None


def _no_semantics(skeleton, evidence=None) -> Tensor:
    """The semantic features of a module trained without them."""
    return torch.zeros(skeleton.num_joints, 0)


def count_parameters(module: nn.Module) -> int:
    """Number of trainable parameters."""
    return sum(p.numel() for p in module.parameters() if p.requires_grad)

