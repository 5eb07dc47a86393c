# SPDX-License-Identifier: BSD-3-Clause
"""The CT job's pipeline on the bundled head CT (Data/ct/headsq.vti), shared by the CT demo and the
CT benchmark: TissueModelFromCT, an ROI on the anterior mandible, a Bezier cut across it and the
soft tissue's deformation. In this CT, z grows towards the chin and the face looks towards -y."""
from paraview import simple

# The cut: a flat surface across the chin (the bone below it, towards larger z, goes).
CUT_Z = 129.0
CURVE_U = [70, 30, CUT_Z, 85, 30, CUT_Z, 100, 30, CUT_Z, 115, 30, CUT_Z]
CURVE_V = [70, 30, CUT_Z, 70, 45, CUT_Z, 70, 60, CUT_Z, 70, 75, CUT_Z]
ROI_CENTER = [92.0, 45.0, 125.0]
ROI_RADIUS = 25.0


def build_model(data_dir, cell_size, surface_distance=2.5, seed=0):
    """Returns (ct, model) proxies; LoadPlugin must have run first."""
    ct = simple.XMLImageDataReader(registrationName="headsq.vti", FileName=[data_dir + "/ct/headsq.vti"])
    model = simple.TissueModelFromCT(registrationName="TissueModelFromCT", Input=ct)
    model.CellSize = cell_size
    model.SurfaceDistance = surface_distance
    model.Seed = seed
    return ct, model


def build(data_dir, cell_size=10.0, surface_distance=2.5):
    """Returns (ct, model, roi, cut, fem) proxies."""
    ct, model = build_model(data_dir, cell_size, surface_distance)
    roi = simple.ROIExtract(registrationName="ROIExtract", Input=simple.OutputPort(model, 1))
    roi.Region = "Sphere"
    roi.Region.Center = ROI_CENTER
    roi.Region.Radius = ROI_RADIUS
    cut = simple.BezierCut(registrationName="BezierCut", Input=roi)
    cut.CurveU = CURVE_U
    cut.CurveV = CURVE_V
    fem = simple.CondensedFEMDeform(registrationName="CondensedFEMDeform", Input=simple.OutputPort(model, 0),
                                    Bone=cut)
    # The bone surface is made of the tissue's own facets: its points coincide with tissue points.
    fem.ContactDistance = 0.01
    # The linear model: on this coarse CT mesh (3.2 mm voxels, CellSize 10 mm) the cut strains a few
    # cells by about 300 %, where the large-deformation model (what Auto would pick) takes minutes
    # with either solver. The demo shows the CT workflow; its strain warning says the picture near
    # the cut is qualitative.
    fem.Model = "LinearElastic"
    return ct, model, roi, cut, fem
