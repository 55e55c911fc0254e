"""Feature normalisation with statistics stored as module buffers (so they
travel inside checkpoints).

Lengths can be measured in character heights before the statistics are
taken (:attr:`FeatureNormalizer.body_relative`): a 5 cm spider and a 3 m
giraffe that walk alike then have alike features, and a latent decoded onto
another body moves it in its own body lengths. The root's lengths (ground
speed and height) can be measured in leg lengths instead
(:attr:`FeatureNormalizer.root_unit`), the unit in which travel compares
across body plans."""
from __future__ import annotations

from typing import Dict, Iterable, List, Optional, Sequence, Union

import numpy as np
import torch
from torch import Tensor, nn

from satagraph.data.features import (DYNAMIC_CHANNELS, DYNAMIC_LAYOUT,
                                     ROOT_CHANNELS, STATIC_CHANNELS,
                                     MotionFeatures)

_EPS = 1e-4

#: Channels of each feature group that are lengths (or lengths per second):
#: ``x``, ``x_rel`` and ``v_x`` of the dynamic features, the root's x/z
#: velocity and height, and both static offsets.
LENGTH_CHANNELS: Dict[str, List[int]] = {
    "dynamic": [*range(DYNAMIC_LAYOUT["x"].start, DYNAMIC_LAYOUT["x_rel"].stop),
                *range(DYNAMIC_LAYOUT["v_x"].start, DYNAMIC_LAYOUT["v_x"].stop)],
    "root": [1, 2, 3],
    "static": list(range(STATIC_CHANNELS)),
}
#: Units of the root's length channels: ``"height"`` (the character height,
#: as every other length) or ``"leg"`` (:func:`satagraph.motion.leg_length`).
ROOT_UNITS = ("height", "leg")
#: Largest accepted mean or standard deviation of any feature channel
#: (features are in metres, seconds and radians after canonicalisation).
MAX_STAT = 1e5


class NormalizerError(ValueError):
    """Statistics that would blind or break a model (non-finite or absurd);
    the message names the file with the most extreme values."""


class FeatureNormalizer(nn.Module):
    r"""Per-channel mean/std pooled over frames and joints (SAME's scheme).

    Dynamic joint features are normalised except the contact column; root
    features ``r`` and static features ``[X_l, X_g]`` have their own
    statistics. Statistics come from the training split only
    (:meth:`fit`) and are saved with the model.

    Args:
        body_relative (bool, optional): Divide the length channels
            (:data:`LENGTH_CHANNELS`) by the character height of each row
            before normalising (and multiply after denormalising), so that
            models see every body in its own heights. Stored as a buffer:
            checkpoints written before it existed load as ``False``.
        root_unit (str, optional): With :obj:`body_relative`, the unit of
            the root's length channels (its ground speed and height): the
            character height (``"height"``, default) or the leg length
            (``"leg"``), so that a body decoded onto another travels as many
            of its own leg lengths as the source did. Stored as the buffer
            ``root_in_legs``: checkpoints written before it existed load as
            ``"height"``.
    """

    def __init__(self, body_relative: bool = True, root_unit: str = "height") -> None:
        super().__init__()
        for name, width in (("dynamic", DYNAMIC_CHANNELS), ("root", ROOT_CHANNELS),
                            ("static", STATIC_CHANNELS)):
            self.register_buffer(f"{name}_mean", torch.zeros(width))
            self.register_buffer(f"{name}_std", torch.ones(width))
        self.register_buffer("fitted", torch.zeros((), dtype=torch.bool))
        self.register_buffer("body_relative", torch.tensor(bool(body_relative)))
        if root_unit not in ROOT_UNITS:
            raise ValueError(f"FeatureNormalizer: root_unit must be one of {ROOT_UNITS}, "
                             f"got {root_unit!r}")
        self.register_buffer("root_in_legs", torch.tensor(root_unit == "leg"))
        for name, columns in LENGTH_CHANNELS.items():
            width = getattr(self, f"{name}_mean").numel()
            mask = torch.zeros(width, dtype=torch.bool)
            mask[columns] = True
            self.register_buffer(f"_{name}_lengths", mask, persistent=False)

    def _load_from_state_dict(self, state_dict, prefix, *args, **kwargs) -> None:
        # statistics saved before body_relative existed are in metres
        if prefix + "fitted" in state_dict:
            state_dict.setdefault(prefix + "body_relative", torch.tensor(False))
            state_dict.setdefault(prefix + "root_in_legs", torch.tensor(False))
        super()._load_from_state_dict(state_dict, prefix, *args, **kwargs)

    @torch.no_grad()
    def fit(self, features: Iterable[MotionFeatures],
            names: Optional[Sequence[str]] = None) -> "FeatureNormalizer":
        """Compute statistics from the (training) features.

        Args:
            features: The training features.
            names: Their files, for error messages.

        Raises:
            NormalizerError: A statistic is non-finite or larger than
                :data:`MAX_STAT` (one extreme file would blind the model to
                every other); the message names the most extreme file.
        """
        feats = list(features)
        if not feats:
            raise ValueError("FeatureNormalizer.fit: no training features")
        stats = {}
        for name in ("dynamic", "root", "static"):
            moments = _Moments()
            for f in feats:  # one file's values at a time: no copy of the whole split
                moments.add(self._fit_values(f, name))
            stats[name] = moments.stats()
            _check_stats(name, stats[name],
                         (_extreme(self._fit_values(f, name)) for f in feats), names)
        self.set_stats(stats)
        return self

    def _fit_values(self, feats: MotionFeatures, name: str) -> np.ndarray:
        """The rows of group :obj:`name` of one file that :meth:`fit` pools.

        Shapes:
            - **return**: :math:`(R, C)`
        """
        if name == "dynamic":
            return self._relative(feats.dynamic.reshape(-1, DYNAMIC_CHANNELS), name,
                                  feats.height)
        if name == "root":
            return self._relative(feats.r, name, feats.height, self._leg(feats))
        return self._relative(feats.static, name, feats.height)

    @torch.no_grad()
    def set_stats(self, stats: Dict[str, tuple]) -> None:
        """Set statistics from ``{name: (mean, std)}``; contacts stay raw."""
        for name, (mean, std) in stats.items():
            mean = torch.as_tensor(np.asarray(mean), dtype=torch.float32)
            std = torch.as_tensor(np.asarray(std), dtype=torch.float32).clamp(min=_EPS)
            if name == "dynamic":
                c = DYNAMIC_LAYOUT["c"]
                mean[c], std[c] = 0.0, 1.0
            getattr(self, f"{name}_mean").copy_(mean)
            getattr(self, f"{name}_std").copy_(std)
        self.fitted.fill_(True)

    def stats(self) -> Dict[str, tuple]:
        """Statistics as plain lists (for JSON or hyperparameters)."""
        return {name: (getattr(self, f"{name}_mean").tolist(),
                       getattr(self, f"{name}_std").tolist())
                for name in ("dynamic", "root", "static")}

    @property
    def root_unit(self) -> str:
        """The unit of the root's length channels (:data:`ROOT_UNITS`)."""
        return "leg" if bool(self.root_in_legs) else "height"

    def _unit(self, name: str, height: Union[None, float, Tensor],
              leg: Union[None, float, Tensor]) -> Union[None, float, Tensor]:
        """The unit that group :obj:`name`'s lengths are measured in: the
        leg length for the root when :attr:`root_unit` is ``"leg"``, else
        the height."""
        if name != "root" or not bool(self.root_in_legs):
            return height
        if leg is None and height is not None:
            raise ValueError("FeatureNormalizer: root lengths are in leg lengths "
                             "(root_unit='leg'); pass leg= with height=")
        return leg

    def _leg(self, feats: MotionFeatures) -> Optional[float]:
        """The leg length of :obj:`feats` where the root is measured in
        it (``None`` otherwise: not computed)."""
        return feats.leg_length if bool(self.root_in_legs) else None

    def _relative(self, value: np.ndarray, name: str, height: float,
                  leg: Optional[float] = None) -> np.ndarray:
        """Length channels of numpy features in character heights (the
        root's in leg lengths when :attr:`root_unit` is ``"leg"``)."""
        if not bool(self.body_relative):
            return value
        out = np.array(value, dtype=np.float64, copy=True)
        out[..., LENGTH_CHANNELS[name]] /= max(float(self._unit(name, height, leg)), 1e-8)
        return out

    def _scale(self, name: str, height: Optional[Tensor], leg: Optional[Tensor],
               columns: slice, like: Tensor) -> Optional[Tensor]:
        """Per-row divisor of the length channels, :math:`(R, C)`, or
        ``None`` when lengths stay as they are."""
        unit = self._unit(name, height, leg)
        if unit is None or not bool(self.body_relative):
            return None
        mask = getattr(self, f"_{name}_lengths")[columns]
        unit = unit.to(like).clamp(min=1e-8).unsqueeze(-1)
        return torch.where(mask, unit, torch.ones_like(unit))

    def normalize(self, value: Tensor, name: str, height: Optional[Tensor] = None,
                  leg: Optional[Tensor] = None) -> Tensor:
        """``(value - mean) / std`` over the last dimension, lengths first
        divided by :obj:`height` when :attr:`body_relative` (the root's by
        :obj:`leg` when :attr:`root_unit` is ``"leg"``).

        Shapes:
            - **value**: :math:`(R, C)`
            - **height**: :math:`(R,)` character height of each row, optional
            - **leg**: :math:`(R,)` leg length of each row, optional
        """
        scale = self._scale(name, height, leg, slice(None), value)
        if scale is not None:
            value = value / scale
        return (value - getattr(self, f"{name}_mean")) / getattr(self, f"{name}_std")

    def denormalize(self, value: Tensor, name: str, columns: slice = slice(None),
                    height: Optional[Tensor] = None,
                    leg: Optional[Tensor] = None) -> Tensor:
        """Inverse of :meth:`normalize`, optionally for a column range."""
        mean = getattr(self, f"{name}_mean")[columns]
        out = value * getattr(self, f"{name}_std")[columns] + mean
        scale = self._scale(name, height, leg, columns, out)
        return out if scale is None else out * scale


class _Moments:
    r"""Per-channel row count, mean and summed squared deviations, merged
    one block of rows at a time (Chan, Golub and LeVeque's pairwise update,
    in float64): the mean and standard deviation of a whole training split
    without holding all of it at once."""

    def __init__(self) -> None:
        self.count = 0
        self.mean: Optional[np.ndarray] = None
        self.m2: Optional[np.ndarray] = None

    def add(self, values: np.ndarray) -> None:
        """Merge a block of rows.

        Shapes:
            - **values**: :math:`(R, C)`
        """
        values = np.asarray(values, dtype=np.float64)
        count = len(values)
        with np.errstate(all="ignore"):
            mean = values.mean(0) if count else np.zeros(values.shape[-1])
            m2 = np.square(values - mean).sum(0)
            if self.mean is None:
                self.count, self.mean, self.m2 = count, mean, m2
                return
            total = self.count + count
            delta = mean - self.mean
            share = count / total if total else 0.0
            self.mean = self.mean + delta * share
            self.m2 = self.m2 + m2 + np.square(delta) * self.count * share
            self.count = total

    def stats(self) -> tuple:
        """``(mean, std)`` of every row merged (NaN for none)."""
        with np.errstate(all="ignore"):
            if not self.count:
                return self.mean * np.nan, self.m2 * np.nan
            return self.mean, np.sqrt(self.m2 / self.count)


def _extreme(values: np.ndarray) -> float:
    """The largest ``|value|`` of a block (NaN as infinite; 0 when empty)."""
    return float(np.nan_to_num(np.abs(values), nan=np.inf).max()) if values.size else 0.0


def _check_stats(name: str, stats: tuple, extremes: Iterable[float],
                 names: Optional[Sequence[str]]) -> None:
    """Raise :class:`NormalizerError` for non-finite or absurd statistics;
    :obj:`extremes` is each file's largest ``|value|`` (:func:`_extreme`),
    read only then."""
    mean, std = stats
    worst = float(np.nan_to_num(np.maximum(np.abs(mean), std), nan=np.inf).max())
    if worst <= MAX_STAT:
        return
    extreme = list(extremes)
    k = int(np.argmax(extreme))
    where = names[k] if names is not None else f"training file #{k}"
    raise NormalizerError(
        f"normalisation statistics of the {name} features are "
        f"{'non-finite' if not np.isfinite(worst) else f'absurd ({worst:.3g})'}: "
        f"the most extreme file is {where} (largest |value| {extreme[k]:.3g}); "
        "fix or leave out that file")
