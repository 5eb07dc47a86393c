# SPDX-License-Identifier: BSD-3-Clause
"""CondensedFEMDeform with ElementOrder = Quadratic on the Badin face scene (pvpython, headless).

Nearly incompressible tissue (nu = 0.49): the quadratic option runs through the same filter, cache
and contact; outputs stay on the input's points, tied nodes carry the bone's displacement exactly as
with linear elements, and the result is softer than the locking linear one. argv[1] is the plugin,
argv[2] the Data folder.
"""
import sys

import numpy as np
from paraview.simple import *
from vtkmodules.util.numpy_support import vtk_to_numpy

from faceplan_test_util import ErrorCatcher, check, fetch, finish

LoadPlugin(sys.argv[1], ns=globals())
data = sys.argv[2]

tissue = XMLUnstructuredGridReader(FileName=[data + "/face/face_tissue.vtu"])
bone = XMLPolyDataReader(FileName=[data + "/face/mandible.vtp"])
roi = ROIExtract(Input=bone)
roi.Region = "Sphere"
roi.Region.Center = [70, 0, 58]
roi.Region.Radius = 25
calc = Calculator(Input=roi, ResultArrayName="Displacement",
                  Function="ROIMask*(1-ROIBoundary)*(0.5*iHat+0.2*jHat+3*kHat)")
moved_bone = WarpByVector(Input=calc, Vectors=["POINTS", "Displacement"])


def field(out, name):
    a = out.GetFieldData().GetAbstractArray(name)
    return a.GetValue(0) if a is not None else None


def run(order, verify=False):
    fem = CondensedFEMDeform(Input=tissue, Bone=moved_bone, OutputMode="Volume")
    fem.PoissonRatio = 0.49
    fem.ElementOrder = order
    fem.Verify = 1 if verify else 0
    errors = ErrorCatcher(fem)
    fem.UpdatePipeline()
    out = fetch(fem)
    check(not errors.messages, "%s: no errors (%s)" % (order, errors.messages))
    return fem, out, vtk_to_numpy(out.GetPointData().GetArray("Displacement")).copy()


lin_fem, lin, u_lin = run("Linear")
quad_fem, quad, u_quad = run("Quadratic")
n = fetch(tissue).GetNumberOfPoints()
check(quad.GetNumberOfPoints() == n, "quadratic output keeps the input's points")
check(np.all(np.isfinite(u_quad)), "quadratic displacements are finite")
check(field(quad, "ElementOrder") == "Quadratic", "field data ElementOrder says Quadratic")
check(field(lin, "ElementOrder") == "Linear", "field data ElementOrder says Linear by default")
check(field(quad, "RelativeResidual") < 1e-9, "quadratic relative residual below 1e-9")
check(field(quad, "ConditionEstimate") > 1.0, "condition estimate reported")
# A 3 mm bone edit strains the tissue: a positive, finite value for both element orders.
quad_strain, lin_strain = field(quad, "LargestStrain"), field(lin, "LargestStrain")
check(quad_strain is not None and lin_strain is not None, "largest strain reported")
check(np.isfinite(quad_strain) and quad_strain > 0.0 and np.isfinite(lin_strain) and lin_strain > 0.0,
      "largest strain positive and finite (quadratic %s, linear %s)" % (quad_strain, lin_strain))
# Tied nodes (prescribed) agree; free nodes move more (linear cells lock, i.e. are too stiff).
tied = np.all(np.abs(u_lin - u_quad) < 1e-12, axis=1) & (np.abs(u_lin).max(axis=1) > 1e-6)
check(tied.sum() > 20, "tied moving nodes carry the same prescribed displacement (%d)" % tied.sum())
moved = np.abs(u_lin).max(axis=1) > 1e-3
check(np.linalg.norm(u_quad[moved]) > np.linalg.norm(u_lin[moved]),
      "quadratic (locking-free) tissue follows the bone more than locking linear tissue")
# An edit (new bone displacement values only) reuses the quadratic precompute.
quad_fem.UpdatePropertyInformation()
count = quad_fem.GetPropertyValue("PrecomputeCount")
calc.Function = "ROIMask*(1-ROIBoundary)*(0.3*iHat+0.1*jHat+2*kHat)"
quad_fem.UpdatePipeline()
quad_fem.UpdatePropertyInformation()
check(quad_fem.GetPropertyValue("PrecomputeCount") == count, "a quadratic edit starts no new precompute")
u_edit = vtk_to_numpy(fetch(quad_fem).GetPointData().GetArray("Displacement"))
check(np.all(np.isfinite(u_edit)) and np.abs(u_edit - u_quad).max() > 1e-3, "the edit changed the result")
finish("TestCondensedFEMDeformQuadratic")
