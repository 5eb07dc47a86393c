# SPDX-License-Identifier: BSD-3-Clause
"""Osteotomy's Operation presets (pvpython, headless): a default-constructed Osteotomy on the face's
maxilla cuts where a Le Fort I does, without the reader having run first (the GUI and pvpython get
the same start); BSSO and Genioplasty cut the mandible where those operations do; every preset marks
its approach (Released, Sliding) and names itself in field data Operation; the presets follow the
anatomical frame (the bone turned with its frame gives the same segment); Custom keeps the planes as
set. argv[1] is the plugin, argv[2] the Data folder.
"""
import sys

import numpy as np
from paraview.simple import *
from vtkmodules.util.numpy_support import vtk_to_numpy

from faceplan_test_util import check, fetch, finish

LoadPlugin(sys.argv[1], ns=globals())
data = sys.argv[2]


def arrays(proxy):
    proxy.UpdatePipeline()
    out = fetch(proxy)
    if out.GetNumberOfPoints() == 0:
        return None
    pd = out.GetPointData()
    p = vtk_to_numpy(out.GetPoints().GetData())
    res = dict(pre=p - vtk_to_numpy(pd.GetArray("Displacement")), seg=vtk_to_numpy(pd.GetArray("SegmentId")) == 1)
    for name in ("Released", "Sliding"):
        a = pd.GetArray(name)
        res[name] = None if a is None else vtk_to_numpy(a) != 0
    op = out.GetFieldData().GetAbstractArray("Operation")
    res["Operation"] = None if op is None else op.GetValue(0)
    return res


def bone_points(name):
    r = XMLPolyDataReader(FileName=[data + "/face/%s.vtp" % name])
    r.UpdatePipeline()
    return vtk_to_numpy(fetch(r).GetPoints().GetData()).copy()


# ------------------------------------------------------------ the default: Le Fort I on the maxilla
maxilla = XMLPolyDataReader(FileName=[data + "/face/maxilla.vtp"])  # not updated: no bounds known yet
default = Osteotomy(Input=maxilla, Translation=[-5, 0, 0])
check(default.Operation == "LeFortI", "a new Osteotomy starts with Operation LeFortI (got %s)" % default.Operation)
a = arrays(default)
check(a is not None, "a default Osteotomy on the maxilla cuts it (no error, output not empty)")
if a is not None:
    P = bone_points("maxilla")
    crest = P[np.argmin(P[:, 2])]
    top = P[np.argmax(P[:, 2])]
    seg, fixed = a["pre"][a["seg"]], a["pre"][~a["seg"]]
    check(len(seg) > 100 and len(fixed) > 100, "Le Fort I: both sides hold bone (%d / %d points)" % (len(seg), len(fixed)))
    cut_z = seg[:, 2].max()
    check(np.all(fixed[:, 2] >= cut_z - 1e-6), "Le Fort I: the cut is horizontal (segment below, fixed bone above)")
    # Above the alveolar process: the cut lies in the upper half of the crest-to-top height, and
    # below the orbits' floor (the top of the maxilla).
    frac = (cut_z - crest[2]) / (top[2] - crest[2])
    check(0.3 < frac < 0.8, "Le Fort I: the cut lies between the alveolar process and the orbits (%.2f of the height)" % frac)
    check(a["Operation"] == "LeFortI", "Le Fort I: field data Operation names the preset")
    check(a["Released"] is not None and a["Released"][~a["seg"]].any() and a["Released"][a["seg"]].any()
          and not a["Released"][a["pre"][:, 2] > top[2] - 5].any()
          and not a["Released"][a["seg"] & (a["pre"][:, 2] < crest[2] + 5)].any(),
          "Le Fort I: the bone above the vestibular incision is degloved (Released) on both sides of the cut, "
          "the alveolar process and the top of the maxilla are not")
    check(not (a["Released"] & a["Sliding"]).any(), "Le Fort I: the teeth are not degloved")
    s = a["Sliding"]
    check(s is not None and s.any() and np.all(a["pre"][s][:, 2] < cut_z) and a["pre"][s][:, 0].min() <= crest[0] + 1e-6,
          "Le Fort I: the teeth (Sliding) are on the segment's front, at the crest")
    # The segment moved by the translation.
    out = fetch(default)
    u = vtk_to_numpy(out.GetPointData().GetArray("Displacement"))
    check(np.allclose(u[a["seg"]], [-5, 0, 0]) and np.allclose(u[~a["seg"]], 0), "Le Fort I: the segment moved, the rest did not")

# ------------------------------------------------------------ BSSO and genioplasty on the mandible
mandible = XMLPolyDataReader(FileName=[data + "/face/mandible.vtp"])
P = bone_points("mandible")
pog, menton, condyle = P[np.argmin(P[:, 0])], P[np.argmin(P[:, 2])], P[np.argmax(P[:, 2])]


def has(points, x):
    return bool(np.any(np.linalg.norm(points - x, axis=1) < 1e-6))


bsso = Osteotomy(Input=mandible, Operation="BSSO", Translation=[-6, 0, 0])
b = arrays(bsso)
check(b is not None, "BSSO on the mandible cuts it")
if b is not None:
    seg, fixed = b["pre"][b["seg"]], b["pre"][~b["seg"]]
    check(has(seg, pog) and has(seg, menton) and has(fixed, condyle),
          "BSSO: the body (pogonion, menton) moves, the rami (condyle) stay")
    check(np.ptp(seg[:, 0]) > 0 and seg[:, 0].max() <= fixed[:, 0].min() + 1e-6, "BSSO: a coronal cut")
    cut_x = seg[:, 0].max()
    check(cut_x > pog[0] + 0.3 * (condyle[0] - pog[0]), "BSSO: the cut is behind the teeth's front, near the rami")
    check(b["Released"] is not None and b["Released"][b["seg"]].any() and b["Released"][~b["seg"]].any(),
          "BSSO: the bone either side of the cut is degloved")
    s = b["Sliding"]
    check(s is not None and s.any() and b["pre"][s][:, 2].min() > menton[2] + 0.5 * (seg[:, 2].max() - menton[2]),
          "BSSO: the teeth (Sliding) are marked on the alveolar process, not the chin")
    check(a is None or b["Operation"] == "BSSO", "BSSO: field data Operation")

genio = Osteotomy(Input=mandible, Operation="Genioplasty", Translation=[-5, 0, 0])
g = arrays(genio)
check(g is not None, "Genioplasty on the mandible cuts it")
if g is not None:
    seg, fixed = g["pre"][g["seg"]], g["pre"][~g["seg"]]
    crest_mid = P[(np.abs(P[:, 1]) < 4) & (P[:, 0] < 80)]
    crest = crest_mid[np.argmax(crest_mid[:, 2])]
    check(has(seg, menton) and has(fixed, crest) and has(fixed, condyle),
          "Genioplasty: the chin (menton) moves, the alveolar process and the rami stay")
    check(seg[:, 2].max() < menton[2] + 0.6 * (crest[2] - menton[2]), "Genioplasty: the cut is below the tooth roots")
    check(np.ptp(seg[:, 1]) < 0.6 * np.ptp(P[:, 1]), "Genioplasty: only the chin, not the mandible's body")
    check(g["Released"] is not None and g["Released"].any() and not g["Released"][g["seg"]].any(),
          "Genioplasty: the fixed anterior mandible is degloved, the chin keeps its tissue")

# ------------------------------------------------------------ the frame: a turned bone, same cut
turn = Transform(Input=mandible)
turn.Transform.Rotate = [0, 0, 90]  # x -> y, y -> -x
turned = Osteotomy(Input=turn, Operation="BSSO", AnteriorDirection=[0, -1, 0], SuperiorDirection=[0, 0, 1])
t = arrays(turned)
check(t is not None and b is not None and t["seg"].sum() == b["seg"].sum(),
      "BSSO on the mandible turned with its frame moves the same points (%s vs %s)"
      % (None if t is None else t["seg"].sum(), None if b is None else b["seg"].sum()))
wrong = Osteotomy(Input=mandible, Operation="BSSO", AnteriorDirection=[1, 0, 0])
check(arrays(wrong) is None, "BSSO with the face turned backwards finds no ramus behind the body: an error, not a cut")

# ------------------------------------------------------------ Custom: the planes as set
custom = Osteotomy(Input=mandible, Operation="Custom")
custom.CutPlane1.Origin, custom.CutPlane1.Normal = [97, 0, 80], [-1, 0, 0]
c = arrays(custom)
check(c is not None and b is not None and abs(c["pre"][c["seg"]][:, 0].max() - 97) < 1e-6,
      "Custom: the cut follows Cut Plane 1")
check(c is not None and c["Released"] is None and c["Operation"] is None,
      "Custom: no approach marked, no Operation field")

finish("TestOsteotomyPresets")
