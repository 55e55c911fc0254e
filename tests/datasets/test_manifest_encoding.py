"""Manifests are UTF-8 whatever the system's encoding (Windows: cp1252)."""
from __future__ import annotations

import builtins
from pathlib import Path
from typing import Any

import pytest

from satagraph.datasets import captions, sources


def _cp1252_open(*args: Any, **kwargs: Any) -> Any:
    """:func:`open` as on Windows: text in cp1252 unless told otherwise."""
    kwargs.setdefault("encoding", "cp1252")
    return builtins.open(*args, **kwargs)


@pytest.mark.parametrize("bom", ["", "\ufeff"])
def test_a_utf8_manifest_reads_alike_on_windows(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                bom: str) -> None:
    """A clip in ``données/`` was looked for in ``donnÃ©es/`` (not found)."""
    clip = tmp_path / "données" / "marche.bvh"
    clip.parent.mkdir()
    clip.write_text("HIERARCHY\n")
    manifest = tmp_path / "manifest.tsv"
    manifest.write_text(f"{bom}path\tdataset\tsplit\ndonnées/marche.bvh\tmes clips\ttrain\n",
                        encoding="utf-8")
    for module in (sources, captions):
        monkeypatch.setattr(module, "open", _cp1252_open, raising=False)
    (row,) = sources.read_manifest(manifest)
    assert Path(row.path) == clip and row.dataset == "mes clips"
    assert captions.read_manifest_rows(manifest)[0]["path"] == "données/marche.bvh"
