# SPDX-License-Identifier: BSD-3-Clause
"""Soft:hard movement ratios of FacePlan's predictions over a sweep of plans, against the published
clinical bands (docs/CLINICAL.md). Each operation is the model a user gets from Osteotomy's Operation
preset and CondensedFEMDeform's defaults (scripts/osteotomy_scenes.py: the preset's cut, Released and
Sliding; ContactModel, LipSeal and Model Auto, which take the preset's arrays, close the lips and
solve for large deformations; LiftOff), moved by advancements of 2-10 mm,
setbacks, impactions and small rotations; FacialLandmarks measures the landmarks. Writes
<out>/sweep.csv and <out>/ratios.png (ratio against movement, the bands shaded) and prints the
table.

    pvpython scripts/clinical_sweep.py <FacePlan.so> <Data dir> <out dir> [--linear] [--quick]
"""
import argparse
import csv
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paraview import simple  # noqa: E402

import osteotomy_scenes  # noqa: E402

parser = argparse.ArgumentParser()
parser.add_argument("plugin")
parser.add_argument("data")
parser.add_argument("out")
parser.add_argument("--linear", action="store_true", help="Model LinearElastic (fast) instead of Auto (NeoHookean on these plans)")
parser.add_argument("--quick", action="store_true", help="advancements of 2, 6 and 10 mm only")
args = parser.parse_args()
simple.LoadPlugin(args.plugin)
os.makedirs(args.out, exist_ok=True)

ADVANCE = [2, 6, 10] if args.quick else [2, 4, 6, 8, 10]
# (label, translation (x forward is -x), rotation degrees) per operation; the face looks towards -x.
PLANS = {
    "lefort1": [("advancement %d mm" % m, [-m, 0, 0], None) for m in ADVANCE]
    + ([] if args.quick else [("setback 3 mm", [3, 0, 0], None), ("impaction 3 mm", [0, 0, 3], None),
                              ("advancement 5 mm, pitch 3 deg", [-5, 0, 0], [0, 3, 0])]),
    "bsso": [("advancement %d mm" % m, [-m, 0, 0], None) for m in ADVANCE]
    + ([] if args.quick else [("setback 3 mm", [3, 0, 0], None), ("setback 6 mm", [6, 0, 0], None),
                              ("advancement 6 mm, pitch 3 deg", [-6, 0, 0], [0, -3, 0])]),
    "genioplasty": [("advancement %d mm" % m, [-m, 0, 0], None) for m in ADVANCE]
    + ([] if args.quick else [("setback 3 mm", [3, 0, 0], None)]),
}
MEASURED = {"lefort1": ["Subnasale", "Pronasale", "LabraleSuperius", "AlarBaseRight", "CheilionRight"],
            "bsso": ["SoftTissuePogonion", "SoftTissueB", "LabraleInferius", "SoftTissueMenton", "CheilionRight"],
            "genioplasty": ["SoftTissuePogonion", "SoftTissueMenton", "SoftTissueB", "LabraleInferius"]}

rows = []
for scene, plans in PLANS.items():
    tissue, bone, osteotomy, skeleton, fem = osteotomy_scenes.build(args.data, scene)
    if args.linear:
        fem.Model = "LinearElastic"
    landmarks = simple.FacialLandmarks(Input=fem, Bone=skeleton, Operation=osteotomy_scenes.SCENES[scene][1])
    for label, translation, rotation in plans:
        osteotomy.Translation = translation
        osteotomy.Rotation = rotation or [0, 0, 0]
        start = time.time()
        landmarks.UpdatePipeline()
        seconds = time.time() - start
        t = landmarks.GetClientSideObject().GetOutputDataObject(0)
        col = {t.GetColumnName(c): t.GetColumn(c) for c in range(t.GetNumberOfColumns())}
        for r in range(t.GetNumberOfRows()):
            name = col["Landmark"].GetValue(r)
            if name not in MEASURED[scene]:
                continue
            rows.append(dict(operation=scene, plan=label, landmark=name, paired=col["PairedBone"].GetValue(r),
                             soft_h=col["Horizontal"].GetValue(r), soft_v=col["Vertical"].GetValue(r),
                             bone_h=col["BoneHorizontal"].GetValue(r), bone_v=col["BoneVertical"].GetValue(r),
                             ratio=col["Ratio"].GetValue(r), band=col["Band"].GetValue(r),
                             source=col["Source"].GetValue(r), check=col["Check"].GetValue(r),
                             seconds=seconds))
        print("%s, %s: solved in %.1f s" % (scene, label, seconds), flush=True)
    for proxy in (landmarks, fem, skeleton, osteotomy):
        simple.Delete(proxy)

with open(os.path.join(args.out, "sweep.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
    w.writeheader()
    for r in rows:
        w.writerow({k: ("%.4f" % v if isinstance(v, float) else v) for k, v in r.items()})
print("\n%-12s %-32s %-19s %7s %7s %6s  %-32s %s" % ("operation", "plan", "landmark", "soft h", "bone h", "ratio",
                                                    "band", "check"))
for r in rows:
    print("%-12s %-32s %-19s %7.2f %7.2f %6.2f  %-32s %s" % (r["operation"], r["plan"], r["landmark"], r["soft_h"],
                                                            r["bone_h"], r["ratio"], r["band"], r["check"]))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

fig, axes = plt.subplots(1, 3, figsize=(15, 4.6), sharey=True)
for ax, scene in zip(axes, PLANS):
    for k, name in enumerate(MEASURED[scene]):
        pts = [r for r in rows if r["operation"] == scene and r["landmark"] == name
               and r["plan"].startswith("advancement") and "deg" not in r["plan"] and r["check"] in ("in", "out", "no band")]
        if not pts:
            continue
        x = [r["bone_h"] for r in pts]
        y = [r["ratio"] for r in pts]
        line, = ax.plot(x, y, "o-", label=name)
        banded = [r for r in pts if r["band"]]
        if banded:
            lo, hi = banded[0]["band"].split()[-1].split("-")
            ax.axhspan(float(lo), float(hi), color=line.get_color(), alpha=0.12)
    ax.set_title({"lefort1": "Le Fort I advancement", "bsso": "BSSO advancement",
                  "genioplasty": "advancement genioplasty"}[scene])
    ax.set_xlabel("bony movement (mm, forward)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
axes[0].set_ylabel("soft:hard ratio (horizontal)")
fig.suptitle("FacePlan's soft:hard ratios (%s model); shaded: the published bands" %
             ("linear" if args.linear else "NeoHookean, LiftOff"))
fig.tight_layout()
fig.savefig(os.path.join(args.out, "ratios.png"), dpi=110)
print("wrote", os.path.join(args.out, "sweep.csv"), "and", os.path.join(args.out, "ratios.png"))
