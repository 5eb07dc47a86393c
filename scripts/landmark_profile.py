# SPDX-License-Identifier: BSD-3-Clause
"""The midline profile before and after a plan, overlaid, with the facial landmarks marked, and the
landmark table as text; shared by the osteotomy demo (scripts/osteotomy_demo.py). Needs a
FacialLandmarks proxy whose inputs are CondensedFEMDeform's output and the bone."""
import numpy as np
from paraview import simple
from vtkmodules.util.numpy_support import vtk_to_numpy

SHORT = {"Pronasale": "Prn", "Subnasale": "Sn", "LabraleSuperius": "Ls", "Stomion": "Sto",
         "LabraleInferius": "Li", "SoftTissueB": "B'", "SoftTissuePogonion": "Pog'", "SoftTissueMenton": "Me'",
         "ANS": "ANS", "APoint": "A", "UpperIncisorTip": "U1", "LowerIncisorTip": "L1", "BPoint": "B",
         "Pogonion": "Pog", "Menton": "Me"}


def table_text(landmarks):
    """The landmark table, one line per landmark."""
    t = landmarks.GetClientSideObject().GetOutputDataObject(0)
    col = {t.GetColumnName(c): t.GetColumn(c) for c in range(t.GetNumberOfColumns())}
    lines = ["%-19s %6s %6s  %-16s %6s %6s  %-34s %s" % ("landmark", "horiz", "vert", "paired bone", "bone h",
                                                         "ratio", "published band", "check")]
    for r in range(t.GetNumberOfRows()):
        if not col["Found"].GetValue(r):
            lines.append("%-19s not found: %s" % (col["Landmark"].GetValue(r), col["Note"].GetValue(r)))
            continue
        ratio = col["Ratio"].GetValue(r)
        defined = col["Check"].GetValue(r) in ("in", "out", "no band")
        lines.append("%-19s %6.2f %6.2f  %-16s %6.2f %6s  %-34s %s" % (
            col["Landmark"].GetValue(r), col["Horizontal"].GetValue(r), col["Vertical"].GetValue(r),
            col["PairedBone"].GetValue(r), col["BoneHorizontal"].GetValue(r),
            "%.2f" % ratio if defined else "-", col["Band"].GetValue(r), col["Check"].GetValue(r)))
    return "\n".join(lines)


def _section(proxy, back, y):
    """Segments (n x 2 x 3) of the midsagittal section of a surface, at its pre-operative position
    (back: moved back by its Displacement) or as it is."""
    source = simple.ExtractSurface(Input=proxy)
    if back:
        source = simple.WarpByVector(Input=source, Vectors=["POINTS", "Displacement"], ScaleFactor=-1.0)
    cut = simple.Slice(Input=source)
    cut.SliceType = "Plane"
    cut.SliceType.Origin = [0.0, y, 0.0]
    cut.SliceType.Normal = [0.0, 1.0, 0.0]
    cut.UpdatePipeline()
    data = simple.servermanager.Fetch(cut)
    segments = []
    if data.GetNumberOfPoints() == 0:
        return np.zeros((0, 2, 3))
    p = vtk_to_numpy(data.GetPoints().GetData())
    lines = vtk_to_numpy(data.GetLines().GetData())
    i = 0
    while i < len(lines):
        n = lines[i]
        ids = lines[i + 1:i + 1 + n]
        segments += [(p[a], p[b]) for a, b in zip(ids[:-1], ids[1:])]
        i += n + 1
    for proxy_ in (cut,) + ((source, source.Input) if back else (source,)):
        simple.Delete(proxy_)
    return np.array(segments)


def draw(landmarks, tissue, bone, path, title, y=0.0):
    """Writes the midline profile (skin and bone, before in grey, after in colour) with the landmarks
    (before: open circles, after: filled) to `path`."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    t = landmarks.GetClientSideObject().GetOutputDataObject(0)
    col = {t.GetColumnName(c): t.GetColumn(c) for c in range(t.GetNumberOfColumns())}
    fig, ax = plt.subplots(figsize=(6.4, 7.2))
    for proxy, colour, label in ((tissue, "#c0392b", "skin"), (bone, "#34495e", "bone")):
        for back, style in ((True, dict(colors="#9a9a9a", linewidths=1.2)),
                            (False, dict(colors=colour, linewidths=1.6))):
            seg = _section(proxy, back, y)
            if len(seg):
                ax.add_collection(LineCollection(seg[:, :, [0, 2]], label="%s %s" % (
                    label, "before" if back else "after"), **style))
    for r in range(t.GetNumberOfRows()):
        name = col["Landmark"].GetValue(r)
        if not col["Found"].GetValue(r) or name not in SHORT:
            continue
        pre = [col["Pre"].GetComponent(r, k) for k in range(3)]
        post = [col["Post"].GetComponent(r, k) for k in range(3)]
        skin = col["Kind"].GetValue(r) == "skin"
        c = "#c0392b" if skin else "#34495e"
        ax.plot(pre[0], pre[2], "o", mfc="none", mec="#777777", ms=5)
        ax.plot(post[0], post[2], "o", color=c, ms=4)
        ax.annotate(SHORT[name], (post[0], post[2]), textcoords="offset points",
                    xytext=(-8 if skin else 6, 0), ha="right" if skin else "left", va="center", fontsize=7, color=c)
    ax.set_xlim(15, 130)
    ax.set_ylim(35, 150)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm; the face looks left)")
    ax.set_ylabel("z (mm)")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7, loc="upper right")
    ax.grid(alpha=0.25)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
