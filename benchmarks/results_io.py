"""Writing a benchmark's table (markdown) and data (JSON) side by side."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any


def write_results(out: Path, title: str, text: str, data: Any) -> None:
    """Writes ``# title`` and :obj:`text` to ``out.md`` and :obj:`data` to
    ``out.json`` (numbers numpy or torch hands back become floats)."""
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".md").write_text(f"# {title}\n\n{text}")
    out.with_suffix(".json").write_text(json.dumps(data, indent=1, default=float))
