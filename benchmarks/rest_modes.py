"""Which rest to show the model: auto (line rests re-rested) vs first-frame,
on zoo VALIDATION-stream clips (never in benchmarks/pretrained.py), per rest
dialect; plus a rest-distance statistic per clip."""
import sys, warnings, collections, json
warnings.simplefilter("ignore")
sys.path.insert(0, "benchmarks")
import numpy as np, torch
torch.set_num_threads(1)
from pretrained import TRAIN_SPECIES, HOLDOUT
from satagraph.datasets.zoo.endless import EndlessZoo
from satagraph.pipelines.inference import retarget_canonical
from satagraph.transforms.canonical import canonicalize
from satagraph.experiment.train import load_module
import satagraph.pipelines.inference as I
NEW = I.needs_rest
m = load_module(sys.argv[1] if len(sys.argv) > 1 else "builtin").eval()
zoo = EndlessZoo(species=TRAIN_SPECIES, holdout=HOLDOUT)
def angle(R):
    return np.degrees(np.arccos(np.clip((np.trace(R, axis1=-2, axis2=-1) - 1) / 2, -1, 1)))
rows = []
per = collections.Counter()
for index in range(1500):
    s = zoo.sample(0, index, 120, "val", False)
    if s.species not in ("biped", "quadruped", "bird", "fowl") or s.kind not in ("walk", "trot", "run", "idle", "turn", "back", "side") or per[s.rest] >= 10:
        continue
    per[s.rest] += 1
    c = canonicalize(s.motion, fps=30.)
    kids = [j for j in range(1, c.skeleton.num_joints) if c.skeleton.children[j]]
    dist = float(np.median(angle(c.rotations[:, kids])))
    r = {"rest": s.rest, "species": s.species, "kind": s.kind, "dist": dist}
    for mode in ("old", "auto", "first-frame"):
        import satagraph.pipelines.inference as I
        I.needs_rest = I.is_line_rest if mode == "old" else NEW
        src, out = retarget_canonical(m, s.motion, s.motion, m.embed, ground=False, rest="auto" if mode == "old" else mode)
        gs, go = src.global_positions(), out.global_positions(); n = min(len(gs), len(go))
        h = src.height()
        r[mode] = float(np.linalg.norm((gs[:n] - gs[:n, :1]) - (go[:n] - go[:n, :1]), axis=-1).mean() / h)
    rows.append(r)
    if sum(per.values()) >= 70: break
json.dump(rows, open("/tmp/s25/reststudy.json", "w"))
by = collections.defaultdict(list)
for r in rows: by[r["rest"]].append(r)
print("| rest | n | root-relative JP, old auto (median) | new auto | first-frame | new auto better than old |")
for k, v in sorted(by.items()):
    o = np.array([x["old"] for x in v]); a = np.array([x["auto"] for x in v]); f = np.array([x["first-frame"] for x in v])
    print(f"| {k} | {len(v)} | {100*np.median(o):.1f} | {100*np.median(a):.1f} | {100*np.median(f):.1f} | {int((a < o - 1e-9).sum())}/{len(v)} (worse {int((a > o + 1e-9).sum())}) |")
allo = np.array([x["old"] for x in rows]); alla = np.array([x["auto"] for x in rows]); allf = np.array([x["first-frame"] for x in rows])
print(f"| all | {len(rows)} | {100*np.median(allo):.1f} | {100*np.median(alla):.1f} | {100*np.median(allf):.1f} | mean {100*allo.mean():.1f} / {100*alla.mean():.1f} / {100*allf.mean():.1f} |")
