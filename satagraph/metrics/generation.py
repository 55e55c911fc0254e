r"""Metrics of text-to-motion generation (issue 19, item 8), as pure
functions of embeddings (numpy, float64).

They follow the HumanML3D protocol (Guo et al. 2022) on the embeddings of
any evaluator (``benchmarks/t2m.py`` trains one on a skeleton-agnostic
descriptor):

- :func:`r_precision`: the paired motion's rank among a pool of
  :data:`POOL_SIZE` texts (the pool size is part of the definition);
- :func:`matching_score`: mean distance between paired embeddings;
- :func:`fid`: Frechet distance of Gaussian fits;
- :func:`kid`: unbiased squared MMD with the cubic polynomial kernel
  (Binkowski et al. 2018), which, unlike FID, has no bias with few samples;
- :func:`diversity`, :func:`multimodality`: mean distances of random pairs
  (all generations, and generations of one text);
- :func:`replicate`: mean and 95% half-width over replications.
"""
from __future__ import annotations

from typing import Callable, Dict, Sequence, Tuple

import numpy as np

#: Texts per retrieval pool (HumanML3D's batch of 32).
POOL_SIZE = 32


def pairwise_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    r"""Euclidean distances between rows.

    Shapes:
        - **a**: :math:`(N, D)`; **b**: :math:`(M, D)`
        - **output**: :math:`(N, M)`
    """
    sq = (a * a).sum(1)[:, None] + (b * b).sum(1)[None] - 2.0 * a @ b.T
    return np.sqrt(np.maximum(sq, 0.0))


def r_precision(text: np.ndarray, motion: np.ndarray, top_k: int = 3,
                pool_size: int = POOL_SIZE, rng: np.random.Generator = None) -> np.ndarray:
    r"""Share of motions whose own text ranks within the first
    1..:obj:`top_k` among a pool of :obj:`pool_size` texts (the pairs are
    shuffled, cut into pools; a last incomplete pool is left out). Texts
    exactly as near as the motion's own (a caption repeated in the pool)
    rank in a random order among themselves, counted by its expectation:
    an own text tied with :math:`m` others after :math:`c` closer ones
    adds :math:`\mathrm{clip}((k - c) / (m + 1), 0, 1)` to R@k, so that
    embeddings that tell no text apart score chance (:math:`k` / pool_size),
    not 1.

    Args:
        text: Text embeddings, row i paired with motion i.
        motion: Motion embeddings.
        top_k: Largest rank counted.
        pool_size: Texts per pool.
        rng: Shuffle of the pairs (default: none).

    Shapes:
        - **text**, **motion**: :math:`(N, D)`, :math:`N \ge` pool_size
        - **output**: :math:`(top\_k,)`, R@1 .. R@top_k
    """
    order = np.arange(len(text)) if rng is None else rng.permutation(len(text))
    pools = len(text) // pool_size
    if pools == 0:
        raise ValueError(f"r_precision needs at least {pool_size} pairs, got {len(text)}")
    hits = np.zeros(top_k)
    for p in range(pools):
        idx = order[p * pool_size:(p + 1) * pool_size]
        dist = pairwise_distances(motion[idx], text[idx])
        own = np.diag(dist)[:, None]
        tie = np.isclose(dist, own, rtol=1e-9, atol=1e-12)
        closer = ((dist < own) & ~tie).sum(1)
        ties = tie.sum(1)  # the own text and those as near
        hits += np.array([np.clip((k - closer) / ties, 0.0, 1.0).sum()
                          for k in range(1, top_k + 1)])
    return hits / (pools * pool_size)


def matching_score(text: np.ndarray, motion: np.ndarray) -> float:
    r"""Mean distance between paired text and motion embeddings.

    Shapes:
        - **text**, **motion**: :math:`(N, D)`
    """
    return float(np.linalg.norm(text - motion, axis=1).mean())


def fid(real: np.ndarray, fake: np.ndarray) -> float:
    r"""Frechet distance between Gaussian fits of two sets of embeddings.

    Shapes:
        - **real**: :math:`(N, D)`; **fake**: :math:`(M, D)`
    """
    mu1, mu2 = real.mean(0), fake.mean(0)
    s1 = np.atleast_2d(np.cov(real, rowvar=False))
    s2 = np.atleast_2d(np.cov(fake, rowvar=False))
    diff = mu1 - mu2
    return float(diff @ diff + np.trace(s1) + np.trace(s2) - 2.0 * trace_sqrt_product(s1, s2))


def _psd_sqrt(cov: np.ndarray) -> np.ndarray:
    """Symmetric square root of a positive semi-definite matrix."""
    vals, vecs = np.linalg.eigh(cov)
    return (vecs * np.sqrt(np.clip(vals, 0.0, None))) @ vecs.T


def trace_sqrt_product(s1: np.ndarray, s2: np.ndarray) -> float:
    r""":math:`\mathrm{tr}\sqrt{S_1 S_2}` of two covariances, as
    :math:`\sum_i \sqrt{\lambda_i(S_1^{1/2} S_2 S_1^{1/2})}` (symmetric,
    so no complex square root).

    Shapes:
        - **s1**, **s2**: :math:`(D, D)`
    """
    root = _psd_sqrt(s1)
    vals = np.linalg.eigvalsh(root @ s2 @ root)
    return float(np.sqrt(np.clip(vals, 0.0, None)).sum())


def kid(real: np.ndarray, fake: np.ndarray) -> float:
    r"""Kernel inception distance: unbiased squared MMD with the kernel
    :math:`k(x, y) = (x^\top y / D + 1)^3`.

    Shapes:
        - **real**: :math:`(N, D)`; **fake**: :math:`(M, D)`, both :math:`\ge 2`
    """
    dim = real.shape[1]
    kxx = (real @ real.T / dim + 1.0) ** 3
    kyy = (fake @ fake.T / dim + 1.0) ** 3
    kxy = (real @ fake.T / dim + 1.0) ** 3
    n, m = len(real), len(fake)
    xx = (kxx.sum() - np.trace(kxx)) / (n * (n - 1))
    yy = (kyy.sum() - np.trace(kyy)) / (m * (m - 1))
    return float(xx + yy - 2.0 * kxy.mean())


def diversity(motion: np.ndarray, pairs: int = 300,
              rng: np.random.Generator = None) -> float:
    r"""Mean distance between :obj:`pairs` random pairs of embeddings
    (drawn with replacement, a row never paired with itself).

    Shapes:
        - **motion**: :math:`(N, D)`, :math:`N \ge 2`
    """
    rng = np.random.default_rng(0) if rng is None else rng
    first = rng.integers(len(motion), size=pairs)
    second = (first + rng.integers(1, len(motion), size=pairs)) % len(motion)
    return float(np.linalg.norm(motion[first] - motion[second], axis=1).mean())


def multimodality(groups: Sequence[np.ndarray], pairs: int = 10,
                  rng: np.random.Generator = None) -> float:
    r"""Mean over texts of the :func:`diversity` of the generations of one
    text (:obj:`pairs` pairs each).

    Shapes:
        - **groups**: per text :math:`(G, D)`, :math:`G \ge 2`
    """
    rng = np.random.default_rng(0) if rng is None else rng
    return float(np.mean([diversity(g, pairs, rng) for g in groups]))


def replicate(fn: Callable[[np.random.Generator], float], times: int = 20,
              seed: int = 0) -> Tuple[float, float]:
    """Mean of :obj:`fn` over :obj:`times` seeded replications and the
    half-width of its 95% confidence interval (1.96 std / sqrt(times))."""
    values = np.array([fn(np.random.default_rng([seed, i])) for i in range(times)])
    return float(values.mean()), float(1.96 * values.std() / np.sqrt(times))


def subsample(x: np.ndarray, size: int, rng: np.random.Generator) -> np.ndarray:
    """:obj:`size` rows drawn without replacement (all, when fewer)."""
    return x if len(x) <= size else x[rng.choice(len(x), size, replace=False)]


def distribution_metrics(real: np.ndarray, fake: np.ndarray, times: int = 10,
                         size: int = 256, seed: int = 0) -> Dict[str, Tuple[float, float]]:
    """FID and KID of :obj:`fake` against :obj:`real` with their 95%
    half-widths over :obj:`times` replications of :obj:`size`-row draws."""
    def draw(fn):
        return replicate(lambda rng: fn(subsample(real, size, rng),
                                        subsample(fake, size, rng)), times, seed)
    return {"fid": draw(fid), "kid": draw(kid)}


__all__ = ["POOL_SIZE", "diversity", "distribution_metrics", "fid", "kid", "matching_score",
           "multimodality", "pairwise_distances", "r_precision", "replicate", "subsample",
           "trace_sqrt_product"]
