# SPDX-License-Identifier: BSD-3-Clause
"""Reading FacialLandmarks' table in the pvpython tests (not a test)."""
import numpy as np

SKIN = ["Pronasale", "Subnasale", "AlarBaseRight", "AlarBaseLeft", "LabraleSuperius", "Stomion",
        "LabraleInferius", "CheilionRight", "CheilionLeft", "SoftTissueB", "SoftTissuePogonion",
        "SoftTissueMenton"]
BONE = ["ANS", "APoint", "UpperIncisorTip", "LowerIncisorTip", "BPoint", "Pogonion", "Menton"]


def table(proxy):
    """The landmark table as {name: row dict}; {} when the output is empty."""
    proxy.UpdatePipeline()
    t = proxy.GetClientSideObject().GetOutputDataObject(0)
    rows = {}
    if t is None or t.GetNumberOfRows() == 0:
        return rows
    names = [t.GetColumnName(c) for c in range(t.GetNumberOfColumns())]
    for r in range(t.GetNumberOfRows()):
        row = {}
        for c, name in enumerate(names):
            col = t.GetColumn(c)
            if col.GetNumberOfComponents() == 3:
                row[name] = np.array([col.GetComponent(r, k) for k in range(3)])
            else:
                v = col.GetValue(r)
                row[name] = v
        rows[row["Landmark"]] = row
    return rows


def landmark_points(proxy):
    out = proxy.GetClientSideObject().GetOutputDataObject(1)
    return out
