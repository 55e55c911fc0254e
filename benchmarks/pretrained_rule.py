"""The rule that lets a candidate replace the built-in model (issue 16).

`experiments/PRETRAIN.md` sections 31-32 register it before a candidate is
measured; this applies it to the JSON that `benchmarks/pretrained_val.py`
writes (validation material only), so that the verdict is computed, not
read off a table by eye. Against the base column (`builtin`) of the same
run, a candidate passes if:

1. the dog (outside its test split): its median JP is at least 5 % below
   the base's, and its pose error is below the base's;
2. no other group's median JP (zoo biped, quadruped, bird, fowl, Bandai)
   rises more than 5 % above the base's;
3. the retargets: no row's mean steps fall by more than 0.03, no row
   loses travel share in band, and no row's lowest posture falls below 0.9,
   or, on a row where the base's is below 0.9 already, by more than 0.03
   below the base's (PRETRAIN.md section 54: ``posture`` is no longer a
   correlation, and the base reads 0.75-0.85 on its human -> quadruped
   rows).

Of those that pass, the one with the lowest dog median is chosen.

With ``--paired`` (PRETRAIN.md section 35) parts 1 and 2 compare clip by
clip instead, by the median over a group's clips of the candidate's error
over the base's on the same clip: part 1 asks the dog's pose error
(root-relative) for a ratio of at most 0.95, since its JP is dominated by
an integrated root path that diverges clip by clip (section 34: ratios
0.12-3.7 between two checkpoints, the median of them 1.01, while the
group's median fell 21 %); part 2 asks every other group's JP for at most
1.05; of those that pass, the lowest dog ratio is chosen. Results written
before stop 46 lack the per-clip values.

``--no-still-steps`` leaves the steps of the rows whose source stands still
out of part 3: their limb timing is the correlation of limbs that barely
move (+0.02 to +0.10 for every checkpoint measured), where what those rows
check is that the retarget stays (travel, posture). Added in section 35
after its measurement, and said so there.

With ``--aim carriage`` (PRETRAIN.md section 54, registered before its
candidates are measured) part 1 asks instead that the lowest posture of
each row of :data:`CARRIAGE_ROWS` (a human's walk onto a quadruped, whose
forepaws the base holds up like hands) rise by at least 0.05 over the
base's; the dog joins part 2's groups, and the passing candidate with the
largest smaller of those two gains is chosen.

With ``--aim human`` (PRETRAIN.md section 58, registered before its
candidates are measured; needs ``--paired``) part 1 asks Bandai's
validation clips (a human rig never trained on) for a paired JP ratio of at
most 0.95; part 2 keeps the zoo groups at 1.05 and the dog's pose error
(paired) at 1.05; the passing candidate with the lowest Bandai ratio is
chosen.

    .venv/bin/python benchmarks/pretrained_rule.py benchmarks/results/pretrained_val.json [--paired] [--aim carriage|human]
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Dict, List, Optional, Tuple

import numpy as np

#: The group the candidates are trained to improve (part 1).
AIM = "dog (not test)"
#: The groups no candidate may lose on (part 2).
KEPT = ("zoo biped", "zoo quadruped", "zoo bird", "zoo fowl", "bandai (val)")
#: Part 1's least gain, part 2's largest loss (shares of the base's median).
GAIN, LOSS = 0.05, 0.05
#: Part 3: largest fall in mean steps, lowest posture, and its largest
#: fall where the base's is below that already.
STEPS_DROP, POSTURE, POSTURE_DROP = 0.03, 0.9, 0.03
#: ``--aim carriage``: the retarget rows whose lowest posture must rise,
#: and by how much.
CARRIAGE_ROWS, CARRIAGE_GAIN = ("zoo biped -> quadruped", "bandai -> dog"), 0.05
#: ``--aim human``: the group whose error must fall (part 1).
HUMAN = "bandai (val)"
#: How the retarget rows whose source stands still are named (``pretrained_val.py``
#: names them with it).
STILL = "still source:"


def paired_ratio(candidate: Dict, base: Dict, key: str = "jp_clips") -> float:
    """Median over a group's clips of the candidate's error :obj:`key`
    (``jp_clips`` or ``pose_clips``) over the base's on the same clip (the
    groups of one ``pretrained_val.py`` run hold the same clips in the
    same order)."""
    if key not in candidate or key not in base:
        raise ValueError(f"pretrained_rule.py --paired: the results lack per-clip {key} "
                         "(written by pretrained_val.py since stop 46); run it again")
    a, b = np.asarray(candidate[key]), np.asarray(base[key])
    if a.shape != b.shape:
        raise ValueError(f"pretrained_rule.py --paired: {a.size} clips against {b.size}")
    return float(np.median(a / b))


def posture_gain(results: Dict, candidate: str, base: str = "builtin") -> float:
    """``--aim carriage``'s score: the smaller rise of the lowest posture
    over the base's on the rows of :data:`CARRIAGE_ROWS`."""
    got, was = results["retarget"][candidate], results["retarget"][base]
    return min(got[row]["posture"] - was[row]["posture"] for row in CARRIAGE_ROWS)


def failures(results: Dict, candidate: str, base: str = "builtin",
             paired: bool = False, still_steps: bool = True,
             aim: str = "dog") -> List[str]:
    """The parts of the rule :obj:`candidate` breaks, one line each
    (empty: it passes); :obj:`paired`: parts 1 and 2 clip by clip;
    :obj:`still_steps` ``False``: part 3 leaves out the steps of the rows
    whose source stands still; :obj:`aim` ``"carriage"``: part 1 on the
    postures of :data:`CARRIAGE_ROWS`, the dog in part 2."""
    rec, bas = results["reconstruction"][candidate], results["reconstruction"][base]
    out = []
    kept = KEPT
    if aim == "carriage":
        kept = KEPT + (AIM,)
        got, was = results["retarget"][candidate], results["retarget"][base]
        out += [f"part 1: {row} lowest posture {got[row]['posture']:.2f} against "
                f"{was[row]['posture']:.2f}" for row in CARRIAGE_ROWS
                if got[row]["posture"] < was[row]["posture"] + CARRIAGE_GAIN]
    elif aim == "human":
        if not paired:
            raise ValueError("pretrained_rule.py --aim human compares clip by clip: add --paired")
        kept = tuple(g for g in KEPT if g != HUMAN)
        ratio = paired_ratio(rec[HUMAN], bas[HUMAN])
        if ratio > 1 - GAIN:
            out.append(f"part 1: {HUMAN} paired JP ratio {ratio - 1:+.1%} over "
                       f"{len(rec[HUMAN]['jp_clips'])} clips")
        dog = paired_ratio(rec[AIM], bas[AIM], "pose_clips")
        if dog > 1 + LOSS:
            out.append(f"part 2: {AIM} paired pose ratio {dog - 1:+.1%} over "
                       f"{len(rec[AIM]['pose_clips'])} clips")
    elif paired:
        ratio = paired_ratio(rec[AIM], bas[AIM], "pose_clips")
        if ratio > 1 - GAIN:
            out.append(f"part 1: {AIM} paired pose ratio {ratio - 1:+.1%} over "
                       f"{len(rec[AIM]['pose_clips'])} clips")
    elif not (rec[AIM]["median"] <= (1 - GAIN) * bas[AIM]["median"]
              and rec[AIM]["pose"] < bas[AIM]["pose"]):
        out.append(f"part 1: {AIM} JP {100 * rec[AIM]['median']:.1f}, pose "
                   f"{100 * rec[AIM]['pose']:.1f} against {100 * bas[AIM]['median']:.1f}, "
                   f"{100 * bas[AIM]['pose']:.1f}")
    for group in kept:
        if paired:
            ratio = paired_ratio(rec[group], bas[group])
            line = (f"part 2: {group} paired JP ratio {ratio - 1:+.1%} over "
                    f"{len(rec[group]['jp_clips'])} clips")
        else:
            ratio = rec[group]["median"] / bas[group]["median"]
            line = (f"part 2: {group} JP {100 * rec[group]['median']:.2f} against "
                    f"{100 * bas[group]['median']:.2f} ({ratio - 1:+.1%})")
        if ratio > 1 + LOSS:
            out.append(line)
    for row, got in results["retarget"][candidate].items():
        was = results["retarget"][base][row]
        has_steps = still_steps or not row.startswith(STILL)  # a standing source has none
        if has_steps and got["steps"] < was["steps"] - STEPS_DROP:
            out.append(f"part 3: {row} steps {got['steps']:+.2f} against {was['steps']:+.2f}")
        if got["travel_ok"] < was["travel_ok"] - 1e-9:
            out.append(f"part 3: {row} travel in band {got['travel_ok']:.0%} against "
                       f"{was['travel_ok']:.0%}")
        if got["posture"] < min(POSTURE, was["posture"] - POSTURE_DROP):
            out.append(f"part 3: {row} lowest posture {got['posture']:.2f} against "
                       f"{was['posture']:.2f}")
    return out


def aim_score(candidate: Dict, base: Dict, paired: bool, aim: str = "dog") -> float:
    """What the choice among passing candidates minimises: the dog's
    paired pose ratio, or unpaired its median JP; ``aim="human"``: Bandai's
    paired JP ratio."""
    if aim == "human":
        return paired_ratio(candidate[HUMAN], base[HUMAN])
    if paired:
        return paired_ratio(candidate[AIM], base[AIM], "pose_clips")
    return candidate[AIM]["median"]


def verdict(results: Dict, base: str = "builtin", paired: bool = False,
            still_steps: bool = True,
            aim: str = "dog") -> Tuple[Dict[str, List[str]], Optional[str]]:
    """Every candidate's failures and the chosen one (``None``: the base stays)."""
    rec = results["reconstruction"]
    fails = {c: failures(results, c, base, paired, still_steps, aim) for c in rec if c != base}
    passing = [c for c, f in fails.items() if not f]
    if aim == "carriage":
        return fails, max(passing, key=lambda c: posture_gain(results, c, base), default=None)
    chosen = min(passing, key=lambda c: aim_score(rec[c], rec[base], paired, aim), default=None)
    return fails, chosen


def _score_text(results: Dict, candidate: str, base: str, paired: bool, aim: str) -> str:
    """What a candidate is chosen by, as the verdict prints it."""
    rec = results["reconstruction"]
    if aim == "carriage":
        return f"posture gain {posture_gain(results, candidate, base):+.2f}"
    if aim == "human":
        return f"{HUMAN} paired JP ratio {aim_score(rec[candidate], rec[base], True, aim):.3f}"
    if paired:
        return f"{AIM} paired pose ratio {aim_score(rec[candidate], rec[base], True):.3f}"
    return f"{AIM} {100 * rec[candidate][AIM]['median']:.1f}"


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("results", type=Path, help="pretrained_val.py's JSON")
    parser.add_argument("--base", default="builtin", help="the column to beat")
    parser.add_argument("--paired", action="store_true",
                        help="parts 1 and 2 clip by clip (medians of per-clip ratios; "
                             "part 1 on the dog's pose error)")
    parser.add_argument("--no-still-steps", action="store_true",
                        help="part 3 leaves out the steps of still-source rows (a source "
                             "that stands has no steps; PRETRAIN.md section 35's amendment, "
                             "written after that section's measurement)")
    parser.add_argument("--aim", choices=("dog", "carriage", "human"), default="dog",
                        help="what part 1 asks a candidate to gain: the dog's error (the "
                             "default), the posture of a human's walk onto a quadruped "
                             "(PRETRAIN.md section 54), or Bandai's error (section 58; "
                             "with --paired)")
    args = parser.parse_args(argv)
    results = json.loads(args.results.read_text())
    try:
        fails, chosen = verdict(results, args.base, args.paired, not args.no_still_steps,
                                args.aim)
    except ValueError as err:
        print(f"{args.results}: {err}", file=sys.stderr)
        return 2
    rec = results["reconstruction"]
    for candidate, lines in fails.items():
        score = _score_text(results, candidate, args.base, args.paired, args.aim)
        print(f"{candidate}: {'passes' if not lines else 'fails'} ({score})")
        for line in lines:
            print(f"    {line}")
    print(f"chosen: {chosen}" if chosen else f"chosen: none ({args.base} stays)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
