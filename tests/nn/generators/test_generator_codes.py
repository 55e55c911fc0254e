"""Code sequences: per-clip padding and the token rate."""
from __future__ import annotations

import pytest
import torch

from satagraph.nn.generators import (code_run_lengths, merge_codes, pool_codes, split_codes,
                                     token_lengths, unpool_codes)
from satagraph.nn.generators.codes import continuation_spans, window_spans


def test_split_and_merge_round_trip():
    frames = torch.tensor([3, 1, 4])
    codes = torch.arange(16).view(8, 2)
    padded = split_codes(codes, frames, pad_value=-1)
    assert padded.shape == (3, 4, 2)
    assert padded[1, 1:].eq(-1).all() and padded[0, 3].eq(-1).all()
    assert torch.equal(padded[2], codes[4:])
    assert torch.equal(merge_codes(padded, frames), codes)


def test_token_lengths_round_up():
    assert token_lengths(torch.tensor([1, 4, 5, 8]), 4).tolist() == [1, 1, 2, 2]


def test_stride_one_only_pads():
    codes = torch.tensor([[1, 2, 3], [4, 5, 6]])
    out, lengths = pool_codes(codes, torch.tensor([3, 2]), 1, pad_value=9)
    assert out.tolist() == [[1, 2, 3], [4, 5, 9]] and lengths.tolist() == [3, 2]


def test_first_and_mode_pooling():
    codes = torch.tensor([[5, 7, 7, 1, 2, 2, 3, 0], [4, 4, 6, 6, 8, 0, 0, 0]])
    lengths = torch.tensor([7, 5])
    first, tok = pool_codes(codes, lengths, 3, "first", pad_value=-1)
    assert tok.tolist() == [3, 2]
    assert first.tolist() == [[5, 1, 3], [4, 6, -1]]
    mode, _ = pool_codes(codes, lengths, 3, "mode", pad_value=-1)
    # window [6, 8, pad]: the padding frame never wins, ties go to the first frame
    assert mode.tolist() == [[7, 2, 3], [4, 6, -1]]


def test_mode_pooling_keeps_one_frames_whole_stack():
    base = torch.tensor([[3, 5, 5, 4]])
    stack = torch.stack([base, torch.tensor([[10, 11, 12, 13]])], -1)
    out, _ = pool_codes(stack, torch.tensor([4]), 4, "mode")
    assert out.tolist() == [[[5, 11]]]  # frame 1: the first frame with the most frequent code


def test_unpool_inverts_pool_on_constant_windows():
    tokens = torch.tensor([[1, 2, 3], [4, 5, 9]])
    frames = torch.tensor([9, 5])
    codes = unpool_codes(tokens, frames, 3, pad_value=9)
    assert codes.tolist() == [[1, 1, 1, 2, 2, 2, 3, 3, 3], [4, 4, 4, 5, 5, 9, 9, 9, 9]]
    back, lengths = pool_codes(codes, frames, 3, pad_value=9)
    assert torch.equal(back, tokens) and lengths.tolist() == [3, 2]
    stacked = unpool_codes(tokens.unsqueeze(-1).expand(-1, -1, 2), frames, 3, pad_value=9)
    assert stacked.shape == (2, 9, 2) and torch.equal(stacked[..., 1], codes)


def test_unknown_reduction_is_refused():
    with pytest.raises(ValueError, match="reduce"):
        pool_codes(torch.zeros(1, 4, dtype=torch.long), torch.tensor([4]), 2, "mean")


def test_run_lengths():
    codes = torch.tensor([[1, 1, 2, 2, 2, 1, 7], [3, 3, 3, 0, 0, 0, 0]])
    assert code_run_lengths(codes, torch.tensor([6, 3])).tolist() == [2, 3, 1, 3]


@pytest.mark.parametrize("length,window,align", [(120, 60, 2), (121, 60, 2), (200, 60, 2),
                                                 (95, 60, 2), (61, 60, 1), (60, 60, 2),
                                                 (7, 60, 2), (250, 64, 4)])
def test_window_spans_take_every_frame_once_from_the_nearest_window(length, window, align):
    """Kept ranges tile the sequence in order; each lies inside its window,
    starts and cuts sit on token boundaries, and no frame is kept from a
    window whose centre is farther than the next window's (by more than a
    token)."""
    spans = window_spans(length, window, align)
    keeps = [(k, m) for _, _, k, m in spans]
    assert keeps[0][0] == 0 and keeps[-1][1] == length
    assert all(a[1] == b[0] and a[0] < a[1] for a, b in zip(keeps, keeps[1:]))
    for i, (start, stop, keep, end) in enumerate(spans):
        assert 0 <= start <= keep < end <= stop <= length and start % align == 0
        assert stop - start <= window + align or len(spans) == 1
        assert keep % align == 0
        centre = (start + stop) / 2
        for j, (s2, e2, _, _) in enumerate(spans):
            other = (s2 + e2) / 2
            for frame in (keep, end - 1):
                if j != i and s2 <= frame < e2:
                    assert abs(frame - centre) <= abs(frame - other) + align
    if length <= window:
        assert spans == [(0, length, 0, length)]
    else:
        assert len(spans) >= 2 and spans[-1][1] == length


def test_window_spans_refuse_a_window_under_two_tokens():
    with pytest.raises(ValueError, match="under two tokens"):
        window_spans(100, 3, 2)


@pytest.mark.parametrize("length,window", [(150, 60), (75, 60), (61, 60), (60, 60), (7, 60),
                                           (181, 60), (9, 3), (200, 17)])
def test_continuation_spans_cover_the_sequence_each_window_after_the_one_before(length, window):
    """The first window starts at 0 and the last ends at the sequence's end;
    every window is a whole window long (but a sequence no longer than one),
    starts before the one before it ends (by at least half a window), keeps
    exactly the tokens already generated and generates at least one."""
    spans = continuation_spans(length, window)
    assert spans[0][0] == 0 and spans[0][2] == 0 and spans[-1][1] == length
    if length <= window:
        assert spans == [(0, length, 0)]
        return
    assert all(stop - start == window for start, stop, _ in spans)
    for (_, end, _), (start, stop, context) in zip(spans, spans[1:]):
        assert context == end - start >= window // 2 and stop > end


def test_continuation_spans_refuse_a_window_under_two_tokens():
    with pytest.raises(ValueError, match="under two tokens"):
        continuation_spans(100, 1)
