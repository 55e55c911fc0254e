"""User captions from sidecar files (HumanML3D .txt, .json)."""
from __future__ import annotations

import json

import pytest

from satagraph.datasets import (Caption, CaptionError, captions_for, parse_humanml3d,
                                read_sidecar, read_sidecars, sidecar_paths)

HUMANML3D = (
    "a man kicks with his left leg.#a/DET man/NOUN kick/VERB with/ADP his/DET "
    "left/ADJ leg/NOUN#0.0#0.0\n"
    "\n"
    "a person steps forward then turns.#a/DET person/NOUN#1.5#3.25\n"
    "someone waves\n")


def test_humanml3d_lines():
    assert parse_humanml3d(HUMANML3D, "clip.txt") == [
        Caption("a man kicks with his left leg.", 0.0, None, "user"),
        Caption("a person steps forward then turns.", 1.5, 3.25, "user"),
        Caption("someone waves", 0.0, None, "user")]


@pytest.mark.parametrize("line, message", [
    ("a person walks#tokens#0.0", r"clip\.txt:2: expected 'caption#tokens#from#to'"),
    ("a person walks#t#x#1.0", r"clip\.txt:2: from 'x' is not a number"),
    ("a person walks#t#2.0#1.0", r"clip\.txt:2: end \(1 s\) must be after start"),
    ("a person walks#t#-1#1.0", r"clip\.txt:2: from must be a finite number >= 0"),
    ("  #t#0.0#0.0", r"clip\.txt:2: empty caption"),
    ("a person walks#t#nan#1", r"clip\.txt:2: from must be a finite"),
])
def test_malformed_txt_names_file_and_line(tmp_path, line, message):
    path = tmp_path / "clip.txt"
    path.write_text("fine#t#0.0#0.0\n" + line + "\n")
    with pytest.raises(CaptionError, match=message) as err:
        read_sidecar(path)
    assert "\n" not in str(err.value) and str(path) in str(err.value)


@pytest.mark.parametrize("suffix", [".txt", ".json"])
def test_a_sidecar_not_in_utf8_names_its_line(tmp_path, suffix):
    """A Latin-1 sidecar was refused with Python's 'position 44', no line."""
    path = tmp_path / f"clip{suffix}"
    text = ("fine#t#0.0#0.0\nune personne fatigu\xe9e#t#0.0#0.0\n" if suffix == ".txt"
            else '[{"text": "fine"},\n {"text": "fatigu\xe9e"}]')
    path.write_bytes(text.encode("latin-1"))
    with pytest.raises(CaptionError, match=rf"clip\{suffix}:2: not UTF-8 text") as err:
        read_sidecar(path)
    assert "\n" not in str(err.value) and str(path) in str(err.value)
    path.write_bytes(b"\xef\xbb\xbf" + text.encode("utf-8"))  # UTF-8 with its BOM: read
    assert read_sidecar(path)[-1].text.startswith(("une personne fatigu\xe9e", "fatigu\xe9e"))


def test_json_sidecar(tmp_path):
    path = tmp_path / "clip.json"
    path.write_text(json.dumps([{"text": "a person jumps", "start": 0.5, "end": 1.25},
                                {"text": "  someone   lands "}, "a bare caption"]))
    assert read_sidecar(path) == [Caption("a person jumps", 0.5, 1.25, "user"),
                                  Caption("someone lands", 0.0, None, "user"),
                                  Caption("a bare caption", 0.0, None, "user")]
    path.write_text(json.dumps({"captions": [{"text": "x", "end": None}]}))
    assert read_sidecar(path) == [Caption("x", 0.0, None, "user")]


@pytest.mark.parametrize("content, message", [
    ('[{"text": "a"},\n {"text": }]', r"clip\.json:2: invalid JSON"),
    ('{"text": "a"}', r"clip\.json: expected a list"),
    ('[{"text": "a", "from": 1}]', r"clip\.json: captions\[0\]: unknown keys \['from'\]"),
    ('[{"text": "a"}, {"text": 3}]', r"clip\.json: captions\[1\]: 'text' must be a string"),
    ('[{"text": "a", "start": 2, "end": 1}]', r"captions\[0\]: end \(1 s\) must be after"),
    ('[{"text": "a", "start": "0"}]', r"captions\[0\]: 'start' must be a number"),
    ('[{"text": "a", "end": true}]', r"captions\[0\]: 'end' must be a number"),
    ('[7]', r"captions\[0\]: expected an object"),
])
def test_malformed_json_names_file_and_item(tmp_path, content, message):
    path = tmp_path / "clip.json"
    path.write_text(content)
    with pytest.raises(CaptionError, match=message) as err:
        read_sidecar(path)
    assert "\n" not in str(err.value)


def test_sidecars_join_templated_captions(tmp_path):
    clip = tmp_path / "bandai" / "dataset-1_bow_sad_001.bvh"
    clip.parent.mkdir()
    clip.write_text("not read")
    assert read_sidecars(clip) == [] and sidecar_paths(clip) == []
    clip.with_suffix(".txt").write_text("a sad bow#a/DET#0.0#0.0\n")
    clip.with_suffix(".json").write_text('[{"text": "bows slowly", "end": 2}]')
    captions = captions_for(clip, count=2, seed=0)
    assert [c.source for c in captions] == ["user", "user", "bandai", "bandai"]
    assert captions[:2] == [Caption("a sad bow"), Caption("bows slowly", 0.0, 2.0)]
    assert [c.source for c in captions_for(clip, user=False)] == ["bandai"] * 10
    assert [c.text for c in captions_for(clip, generated=False)] == ["a sad bow",
                                                                    "bows slowly"]
    # A manifest row's path is relative to root.
    row = {"path": "bandai/dataset-1_bow_sad_001.bvh", "dataset": "bandai"}
    assert captions_for(row, root=tmp_path, count=0) == captions[:2]


def test_dog_clips_only_have_user_captions(tmp_path):
    clip = tmp_path / "dog" / "D1_001_KAN01_001.bvh"
    clip.parent.mkdir()
    assert captions_for(clip) == []
    clip.with_suffix(".txt").write_text("a dog trots forward#x#0#0\n")
    assert captions_for(clip) == [Caption("a dog trots forward", 0.0, None, "user")]


def test_caption_frames():
    assert Caption("x").frames(30.0, 90) == slice(0, 90)
    assert Caption("x", 1.0, 2.0).frames(30.0, 90) == slice(30, 60)
    assert Caption("x", 2.5, 9.0).frames(30.0, 90) == slice(75, 90)
    assert Caption("x", 4.0, 5.0).frames(30.0, 90) == slice(90, 90)
