"""A caption of a clip (or of a part of it) and the seeded choice of
phrasings."""
from __future__ import annotations

import zlib
from dataclasses import dataclass, replace
from typing import List, Optional, Sequence

import numpy as np

from satagraph.datasets.mirror import mirror_text
from satagraph.datasets.reverse import reverse_text


class CaptionError(ValueError):
    """A malformed caption sidecar or caption request; the message names the
    file and line."""


@dataclass(frozen=True)
class Caption:
    r"""One text describing a clip, or the part of it between :attr:`start`
    and :attr:`end`.

    Attributes:
        text (str): The description.
        start (float): Seconds from the clip's first frame.
        end (float, optional): Seconds; ``None`` up to the clip's end.
        source (str): Where it comes from: ``"user"`` (a sidecar file) or
            the template set (``"bandai"``, ``"cmu"``, ``"xia"``,
            ``"ccbase"``, ``"zoo"``).
    """

    text: str
    start: float = 0.0
    end: Optional[float] = None
    source: str = "user"

    @property
    def whole(self) -> bool:
        """Whether the caption describes the whole clip."""
        return self.start == 0.0 and self.end is None

    def mirrored(self) -> "Caption":
        """The caption of the left/right mirrored clip (see
        :func:`~satagraph.datasets.mirror.mirror_text`)."""
        return replace(self, text=mirror_text(self.text))

    def reversed(self) -> Optional["Caption"]:
        """The caption of the clip played backwards, or ``None`` where that is
        not known (see :func:`~satagraph.datasets.reverse.reverse_text`)."""
        text = reverse_text(self.text)
        return None if text is None else replace(self, text=text)

    def frames(self, fps: float, num_frames: int) -> slice:
        """The frames the caption describes.

        Args:
            fps: Frame rate of the clip.
            num_frames: Frames of the clip.

        Returns:
            slice: ``[round(start * fps), round(end * fps))`` within the clip.
        """
        first = min(max(int(round(self.start * fps)), 0), num_frames)
        last = num_frames if self.end is None else int(round(self.end * fps))
        return slice(first, min(max(last, first), num_frames))


def mirror_captions(captions: Sequence[Caption]) -> List[Caption]:
    """The captions of a left/right mirrored clip, to go with
    :func:`~satagraph.transforms.augment.mirror`."""
    return [c.mirrored() for c in captions]


def choose(phrasings: Sequence[str], key: str, seed: int = 0,
           count: Optional[int] = None) -> List[str]:
    """A seeded choice of distinct phrasings of one clip.

    Args:
        phrasings: Every phrasing, in their canonical order (duplicates are
            dropped).
        key: The clip (its file name): different clips draw differently.
        seed: Random seed.
        count: How many; ``None`` (or more than there are) for all of them.

    Returns:
        list[str]: The chosen phrasings, in canonical order. The same for
        the same ``(phrasings, key, seed, count)`` on every machine.
    """
    unique = list(dict.fromkeys(phrasings))
    if count is None or count >= len(unique):
        return unique
    if count < 0:
        raise CaptionError(f"captions: count must be >= 0, not {count}")
    rng = np.random.default_rng([int(seed), zlib.crc32(key.encode("utf-8"))])
    chosen = sorted(rng.choice(len(unique), size=count, replace=False).tolist())
    return [unique[i] for i in chosen]


__all__ = ["Caption", "CaptionError", "choose", "mirror_captions"]
