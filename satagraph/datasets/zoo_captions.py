r"""Templated captions of procedural zoo clips, from what the generator drew.

The truth is the generator's :class:`~satagraph.datasets.zoo.ClipFacts` (body
plan, clip kind, start and end speed, signed turn): an endless-zoo sample
carries them (:attr:`~satagraph.datasets.zoo.endless.ZooSample.facts`) and
``satagraph zoo`` writes them to its manifest (columns
:data:`~satagraph.datasets.zoo.MOTION_COLUMNS`). A manifest written before
those columns existed still names the kind in the file name; its captions
then say only what the kind guarantees (a turn without its side, a speed
change without its sign).

What each kind does (:mod:`satagraph.datasets.zoo.motions`):

* ``walk``: forward at a steady speed; snakes slither. The generator adds
  a drift of at most 4 deg/s, told (as veering) only where it adds up to
  :data:`DRIFT_TURN` degrees.
* ``trot``: a trot (quadrupeds).
* ``turn``: walks forward while turning, from about a third of the way in;
  the side is the sign of the turn (positive: left), the wording its size
  (:data:`TURN_WORDS`; a turn under :data:`UNTOLD_TURN` degrees, as in a
  short window, is told as walking forward).
* ``speed``: walks forward, speeding up or slowing down (about x2).
* ``idle``: stands in place, swaying gently (snakes: lie in place swaying
  the raised front of the body).
* ``start``: stands, then sets off and walks forward (legged plans; the
  change is centred in the clip and takes 1.5 s).
* ``stop``: walks forward, then slows to a halt and stands.
* ``look``: stands in place turning its head, neck, tail and arms slowly
  (legged plans).
* ``jump``: stands, crouches, jumps (up to 0.6 leg lengths forward, or in
  place) and lands (legged plans).
* ``reach``: stands and raises one arm forward or overhead, holds it and
  lowers it again (bipeds).
* ``bow`` (a gesture, drawn only when asked for): stands and bends forward
  at the hips and along the spine, 30-70 degrees, holds and straightens up
  (bipeds).
* ``wave`` (a gesture): stands, raises one arm to the side with the forearm
  up, swings the forearm from side to side and lowers the arm (bipeds).
* ``sit`` (a gesture): stays in place, pitching nose up until the hips are
  down on folded hind legs, stays seated and gets up (quadrupeds; a short
  window may show only part of that).
* ``lie`` (a gesture): stays in place, folding all four legs until the body
  is down near the ground, stays and gets up (quadrupeds; as ``sit``).
* ``back``: walks backward, facing forward (legged plans).
* ``side``: walks facing forward while travelling 30-90 degrees to one side
  (the sign of ``travel``: positive left), told as diagonally forward
  below :data:`SIDESTEP` degrees and as sidestepping above (legged plans).
* ``run``: the gait at 1.8-2.5 times its walking speed (legged plans;
  quadrupeds gallop, at that multiple of the gallop's speed), told as
  dashing from :data:`DASH` times that speed.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import PurePath
from typing import Dict, List, Mapping, Optional, Tuple

from satagraph.datasets.zoo import ALL_KINDS, GAITS, SPECIES, ClipFacts
from satagraph.datasets.zoo.motions import gait_of

#: Body plan -> subjects.
ZOO_SUBJECTS: Dict[str, Tuple[str, ...]] = {
    "biped": ("a person", "a two-legged character"),
    "quadruped": ("a four-legged animal", "a quadruped"),
    "longtail": ("a long-tailed four-legged animal", "a quadruped with a long tail"),
    "bird": ("a bird", "a two-legged bird"),
    "fowl": ("a bird", "a two-legged bird"),
    "hexapod": ("an insect", "a six-legged insect"),
    "crab": ("a crab", "a crab on its walking legs"),
    "spider": ("a spider", "an eight-legged spider"),
    "snake": ("a snake", "a long snake"),
}
#: Turn sizes (degrees, upper bounds) -> how a turn of that size is told.
TURN_WORDS = ((45.0, "veers"), (135.0, "turns"), (225.0, "turns around"),
              (float("inf"), "turns in a circle"))
#: Turns smaller than this (degrees) go untold, whatever the kind; larger
#: drifts of straight kinds (long walks) are told as veering.
UNTOLD_TURN = 10.0
DRIFT_TURN = 30.0
#: ``side`` clips travelling at least this many degrees off the facing
#: direction are told as sidestepping, the others as walking diagonally.
SIDESTEP = 60.0
#: ``run`` clips at least this many times the speed of the gait they run
#: in (:func:`run_speed`) are told as dashing, the others as running.
DASH = 2.15
_KIND_IN_NAME = re.compile(
    r"_(?P<kind>%s)(?:_\d+)?$" % "|".join(sorted(set().union(*ALL_KINDS.values()))))
_SPECIES_IN_NAME = re.compile(r"^zoo\d+-(?P<species>[a-z]+)-")


@dataclass(frozen=True)
class ZooClip:
    """What a zoo clip's captions may say: always the body plan and kind;
    the turn and the direction of travel (degrees, positive: left) and
    speeds where known."""

    species: str
    kind: str
    turn: Optional[float] = None
    speed_start: Optional[float] = None
    speed_end: Optional[float] = None
    travel: Optional[float] = None

    @classmethod
    def of(cls, facts: ClipFacts) -> "ZooClip":
        """From the generator's facts."""
        return cls(facts.species, facts.kind, facts.turn, facts.speed_start,
                   facts.speed_end, facts.travel)


def _number(row: Mapping[str, str], key: str) -> Optional[float]:
    value = row.get(key)
    return None if value in (None, "") else float(value)


def zoo_clip_of_row(row: Mapping[str, str]) -> Optional[ZooClip]:
    """A zoo manifest row's clip: species and kind from their columns (or
    the file name ``zoo<seed>-<species>-..._<kind>.bvh``), the facts from
    their columns when present; ``None`` when the species or kind is
    unknown."""
    stem = PurePath(str(row.get("path", ""))).stem
    in_name = _SPECIES_IN_NAME.match(stem)
    species = row.get("species") or (in_name["species"] if in_name else "")
    match = _KIND_IN_NAME.search(stem)
    kind = row.get("kind") or (match["kind"] if match else "")
    if species not in SPECIES or kind not in ALL_KINDS[species]:
        return None
    return ZooClip(species, kind, _number(row, "turn_deg"), _number(row, "speed_start"),
                   _number(row, "speed_end"), _number(row, "travel_deg"))


def _turn_phrase(turn: Optional[float]) -> Tuple[str, str]:
    """(verb, side) of a turn: ``("turns", "left")``; no side when unknown."""
    if turn is None:
        return "turns", ""
    size = abs(turn)
    verb = next(word for bound, word in TURN_WORDS if size < bound)
    return verb, "left" if turn > 0 else "right"


def _verbs(clip: ZooClip) -> List[str]:
    """Verb phrases of a clip."""
    move = "slithers" if clip.species == "snake" else "walks"
    moving = "slithering" if clip.species == "snake" else "walking"
    drift = _drift(clip)
    if clip.kind == "walk" or (clip.kind == "turn" and clip.turn is not None
                               and abs(clip.turn) < UNTOLD_TURN):
        return [f"{move} forward{drift}", f"{move} forward at a steady pace{drift}"]
    if clip.kind == "trot":
        return [f"trots forward{drift}", f"moves forward at a trot{drift}"]
    if clip.kind == "idle":
        if clip.species == "snake":
            return ["lies in place, swaying the front of its body",
                    "rests with its head raised, swaying gently"]
        return ["stands still, swaying gently", "stands in place"]
    if clip.kind == "start":
        return ["stands still, then starts walking forward",
                "sets off from a standstill and walks forward"]
    if clip.kind == "stop":
        return ["walks forward and comes to a stop", "slows down to a halt and stands still"]
    if clip.kind == "look":
        return ["stands in place, looking around", "stands still, turning its head"]
    if clip.kind == "jump":
        return ["crouches and jumps", "jumps up and lands"]
    if clip.kind == "reach":
        return ["stands and reaches out with one arm", "raises an arm and lowers it again"]
    if clip.kind == "bow":
        return ["bows", "bends forward in a bow"]
    if clip.kind == "wave":
        return ["waves goodbye with one hand", "raises a hand and waves"]
    if clip.kind == "sit":
        return ["sits down on its haunches in place", "lowers its hindquarters and sits"]
    if clip.kind == "lie":
        return ["lies down on the ground in place", "folds its legs and lies down"]
    if clip.kind in ("back", "side", "run"):
        return _travel_verbs(clip, drift)
    if clip.kind == "turn":
        verb, side = _turn_phrase(clip.turn)
        if not side:
            return [f"{move} forward and {verb}", f"{verb} while {moving}"]
        return [f"{move} forward and {verb} to the {side}",
                f"{verb} {side} while {moving}"]
    if clip.speed_start is None or clip.speed_end is None:
        return [f"{move} forward, changing its speed", f"changes speed while {moving}"]
    if clip.speed_end > clip.speed_start:
        return [f"{move} forward, speeding up{drift}",
                f"starts slowly and {move} faster and faster{drift}"]
    return [f"{move} forward, slowing down{drift}",
            f"starts fast and {move} slower and slower{drift}"]


def _travel_verbs(clip: ZooClip, drift: str) -> List[str]:
    """Verb phrases of the walks that do not go straight ahead at a walk."""
    if clip.kind == "run":
        if dashes(clip):
            return [f"dashes forward{drift}", f"sprints forward{drift}"]
        return [f"runs forward{drift}", f"jogs forward{drift}"]
    if clip.kind == "back":
        return [f"walks backward{drift}", f"walks backwards{drift}"]
    if clip.travel is None:
        return ["walks to one side", "walks sideways"]
    side = "left" if clip.travel > 0 else "right"
    if abs(clip.travel) < SIDESTEP:
        return [f"walks forward and to the {side}", f"walks diagonally to the {side}"]
    return [f"steps sideways to the {side}", f"sidesteps to the {side}"]


def run_speed(species: str) -> float:
    """Speed (leg lengths per second) of the gait a species' ``run`` clips
    move in, which they run at 1.8-2.5 times: a quadruped's gallop, every
    other plan's own gait."""
    return GAITS[gait_of(species, "run")][3]


def dashes(clip: ZooClip) -> bool:
    """Whether a ``run`` clip is told as dashing: from :data:`DASH` times
    :func:`run_speed` (a quadruped's gallop, not its walk: against the walk
    every gallop read as a dash)."""
    return (clip.kind == "run" and clip.speed_start is not None
            and clip.speed_start >= DASH * run_speed(clip.species))


def _drift(clip: ZooClip) -> str:
    """``", veering to the left"`` for a straight kind whose small yaw
    rate added up to :data:`DRIFT_TURN` degrees or more; else empty."""
    if clip.kind in ("turn", "idle") or clip.turn is None or abs(clip.turn) < DRIFT_TURN:
        return ""
    return f", veering to the {'left' if clip.turn > 0 else 'right'}"


def zoo_phrasings(clip: ZooClip) -> List[str]:
    """Every phrasing of a zoo clip: its subjects x its verb phrases.

    Args:
        clip: The clip (:meth:`ZooClip.of` a :class:`ClipFacts`, or
            :func:`zoo_clip_of_row`).

    Returns:
        list[str]: The phrasings.
    """
    return [f"{subject} {verb}" for verb in _verbs(clip)
            for subject in ZOO_SUBJECTS[clip.species]]


__all__ = ["ZOO_SUBJECTS", "TURN_WORDS", "UNTOLD_TURN", "DRIFT_TURN", "SIDESTEP", "DASH", "ZooClip", "dashes", "run_speed", "zoo_clip_of_row", "zoo_phrasings"]
