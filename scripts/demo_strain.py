# SPDX-License-Identifier: BSD-3-Clause
"""How far the main demo's plan strains the tissue (pvpython), under the linear and the
large-deformation model: the figures README.md gives beside `scripts/demo`.

    pvpython scripts/demo_strain.py <FacePlan.so> <Data dir> [--contact Tied|Sliding] [--release MM]

--contact and --release set CondensedFEMDeform's ContactModel and ReleaseDistance (the demo's own:
Tied, 0), to see how much of the strain the tissue's ties to the collapsed bone cause.
Runs faceplan_pipeline.build (the demo's ROI, Bezier cut and CondensedFEMDeform, Volume output so
every cell's strain can be taken) with Model LinearElastic, then NeoHookean, and prints for each the
update time, the filter's LargestStrain, the cells beyond 10 % / 50 % strain (small strain for the
linear model, Green-Lagrange for the large-deformation one), the smallest volume ratio and the
Newton iterations where the model reports them, and how far the bone moved.
"""
import argparse
import os
import sys
import time

import numpy as np
from paraview import servermanager
from paraview.simple import LoadPlugin
from vtkmodules.util.numpy_support import vtk_to_numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import faceplan_pipeline  # noqa: E402
import tet_strain  # noqa: E402

parser = argparse.ArgumentParser()
parser.add_argument("plugin")
parser.add_argument("data_dir")
parser.add_argument("--contact", choices=("Tied", "Sliding"), default="Tied")
parser.add_argument("--release", type=float, default=0.0, help="ReleaseDistance (mm)")
args = parser.parse_args()
LoadPlugin(args.plugin)
tissue_proxy, _, _, cut, fem = faceplan_pipeline.build(args.data_dir)
fem.OutputMode = "Volume"
fem.ContactModel = args.contact
fem.ReleaseDistance = args.release
print("ContactModel %s, ReleaseDistance %g mm" % (args.contact, args.release))
tissue = servermanager.Fetch(tissue_proxy)
xyz = vtk_to_numpy(tissue.GetPoints().GetData()).astype(float)
conn = vtk_to_numpy(tissue.GetCells().GetConnectivityArray()).reshape(-1, 4)

for model in ("LinearElastic", "NeoHookean"):
    fem.Model = model
    start = time.perf_counter()
    fem.UpdatePipeline()
    seconds = time.perf_counter() - start
    out = servermanager.Fetch(fem)
    u = vtk_to_numpy(out.GetPointData().GetArray("Displacement")).astype(float)
    strain = tet_strain.largest_principal_strain(xyz, conn, u, green_lagrange=model == "NeoHookean")
    fd = out.GetFieldData()

    def field(name):
        a = fd.GetArray(name)
        return a.GetValue(0) if a else None

    extra = ""
    if field("NewtonIterations") is not None:
        extra = ", %d load step(s), %d Newton iterations, smallest volume ratio %.3f" % (
            field("LoadSteps"), field("NewtonIterations"), field("SmallestVolumeRatio"))
    print("%s: update %.2f s, LargestStrain %.1f %%, cells beyond 10 %%: %d of %d (%.1f %%), beyond "
          "50 %%: %d%s" % (model, seconds, 100 * field("LargestStrain"), (strain > 0.1).sum(),
                            len(strain), 100 * np.mean(strain > 0.1), (strain > 0.5).sum(), extra))

bone = servermanager.Fetch(cut)
moved = np.linalg.norm(vtk_to_numpy(bone.GetPointData().GetArray("Displacement")), axis=1)
print("bone: %d of %d points moved, by up to %.2f mm" % ((moved > 1e-6).sum(), len(moved), moved.max()))
