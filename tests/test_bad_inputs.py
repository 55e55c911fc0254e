"""The fast cases of ``benchmarks/bad_inputs.py`` (hostile BVH files, special
files, output paths, non-checkpoints and planted pickles, tags), run through
the CLI in-process: each ends in a clean error or is handled correctly."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import bad_inputs  # noqa: E402

CASES = bad_inputs.all_cases(Path("/nonexistent"), quick=True)


def test_enough_distinct_cases() -> None:
    full = bad_inputs.all_cases(Path("/nonexistent"))
    assert len(full) >= 120 and len(CASES) >= 90


def _param(case: bad_inputs.Case):
    """A 3000-level hierarchy takes 10-40 s per command: slow."""
    slow = [pytest.mark.slow] if "3000-level" in case.name else []
    return pytest.param(case, id=case.name, marks=slow)


@pytest.mark.parametrize("case", [_param(c) for c in CASES])
def test_bad_input(case: bad_inputs.Case, tmp_path: Path) -> None:
    result = bad_inputs.run_in_process(case, tmp_path)
    expected = "handled" if case.expect == "handled" else "clean error"
    assert result.outcome == expected, ((tmp_path / "stderr").read_text()[-2000:],
                                        result.message)


def test_classify() -> None:
    case = bad_inputs.Case("x", "g", lambda t: [])
    tmp = Path("/nonexistent")
    assert bad_inputs.classify(case, None, "", tmp) == "hang"
    assert bad_inputs.classify(case, 1, "Traceback (most recent call last):\n", tmp) \
        == "traceback"
    assert bad_inputs.classify(case, 0, "", tmp) == "silent wrong"
    assert bad_inputs.classify(case, 2, "satagraph: error: x.bvh:3: bad\n", tmp) \
        == "clean error"
    assert bad_inputs.classify(case, 2, "Killed\n", tmp) == "traceback"
