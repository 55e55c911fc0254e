"""Writing a benchmark's table (markdown) and data (JSON) side by side."""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
from typing import Any, Optional

from satagraph.utils.files import atomic_write_text

#: The real BVH files every benchmark reads by default: ``SATAGRAPH_DATA``
#: where set (as the tests read it), else ``../shared/data`` beside the
#: checkout.
SHARED_DATA = Path(os.environ.get("SATAGRAPH_DATA")
                   or Path(__file__).resolve().parents[2] / "shared" / "data")


def write_results(out: Path, title: str, text: str, data: Any) -> None:
    """Writes ``# title`` and :obj:`text` to ``out.md`` and :obj:`data` to
    ``out.json`` (numbers numpy or torch hands back become floats)."""
    out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out.with_suffix(".md"), f"# {title}\n\n{text}")
    atomic_write_text(out.with_suffix(".json"), json.dumps(data, indent=1, default=float))


def missing_data(script: str, folder: Path = SHARED_DATA, what: str = "the real rows"
                 ) -> Optional[str]:
    """The one line a benchmark that reads the real files prints before it
    stops where :obj:`folder` holds no ``manifest.tsv``; ``None`` where it
    does (one check for every such benchmark)."""
    if (Path(folder) / "manifest.tsv").is_file():
        return None
    return (f"{script}: {folder}: no manifest.tsv there: {what} need the real BVH files of "
            "../shared/data (or $SATAGRAPH_DATA)")


def data_folder(text: str) -> str:
    """The ``--data`` argument of a benchmark that reads the real files: a
    folder holding their ``manifest.tsv`` (``../shared/data``), else one
    usage line saying so (a traceback deep in the reader before)."""
    if not (Path(text) / "manifest.tsv").is_file():
        raise argparse.ArgumentTypeError(
            f"{text}: no manifest.tsv there: this benchmark reads the real BVH files of "
            "../shared/data; pass --data DIR for a folder that has them")
    return text
