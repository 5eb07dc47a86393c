# SPDX-License-Identifier: BSD-3-Clause
"""The main job's pipeline on the Badin face scene, shared by the demo, the image tests and the GUI
test: an ROI on the lower border of the mandible (chin), a Bezier cut that reduces it (as in the
ICAT 2008 paper's Figures 12 and 13) and the soft tissue's deformation."""
from paraview import servermanager, simple

# The cut: a gently curved surface 6 mm above the chin's lowest point (the bone below it goes).
CUT_Z = 60.0
CURVE_U = [40, -30, CUT_Z, 60, -30, CUT_Z - 0.5, 80, -30, CUT_Z - 0.5, 100, -30, CUT_Z]
CURVE_V = [40, -30, CUT_Z, 40, -10, CUT_Z + 0.5, 40, 10, CUT_Z + 0.5, 40, 30, CUT_Z]


def place_cut(cut, dz):
    """Sets the cut surface dz mm above the demo's (dz < 0: a deeper cut, more bone goes)."""
    cut.CurveU = [c + (dz if k % 3 == 2 else 0.0) for k, c in enumerate(CURVE_U)]
    cut.CurveV = [c + (dz if k % 3 == 2 else 0.0) for k, c in enumerate(CURVE_V)]


def build(data_dir):
    """Returns (tissue, mandible, roi, cut, fem) proxies; LoadPlugin must have run first."""
    tissue = simple.XMLUnstructuredGridReader(registrationName="face_tissue.vtu",
                                       FileName=[data_dir + "/face/face_tissue.vtu"])
    mandible = simple.XMLPolyDataReader(registrationName="mandible.vtp",
                                 FileName=[data_dir + "/face/mandible.vtp"])
    roi = simple.ROIExtract(registrationName="ROIExtract", Input=mandible)
    roi.Region = "Sphere"
    roi.Region.Center = [70.0, 0.0, 58.0]
    roi.Region.Radius = 22.0
    cut = simple.BezierCut(registrationName="BezierCut", Input=roi)
    cut.CurveU = CURVE_U
    cut.CurveV = CURVE_V
    cut.FlipNormal = 1  # the surface's normal points down: the bone below is cut away
    fem = simple.CondensedFEMDeform(registrationName="CondensedFEMDeform", Input=tissue, Bone=cut)
    fem.ContactDistance = 1.0
    return tissue, mandible, roi, cut, fem


def drag_render_settings(view):
    """The render view setting README.md recommends while a widget is dragged with Auto Apply:
    FXAA off. ParaView's default FXAA is a full-screen pass whose cost grows with the view's pixels
    and, with software rendering (Mesa llvmpipe), is a large part of every frame; without it edges
    are aliased, nothing else changes. Returns the settings applied (name -> value)."""
    settings = {"UseFXAA": 0}
    for name, value in settings.items():
        view.SetPropertyWithName(name, value)
    return settings


# One colour map and range for displacement, bone and face alike, so the two can be compared.
DISPLACEMENT_RANGE_MM = (0.0, 6.0)


def displacement_colors():
    """The shared Displacement colour map (Turbo, magnitude, fixed 0-6 mm)."""
    lut = simple.GetColorTransferFunction("Displacement")
    lut.ApplyPreset("Turbo", True)
    lut.AutomaticRescaleRangeMode = "Never"
    lut.VectorMode = "Magnitude"
    lut.RescaleTransferFunction(*DISPLACEMENT_RANGE_MM)
    return lut


def label_bar(lut, view, title, position=(0.05, 0.15), length=0.6):
    """Shows lut's colour bar in view with a title (name and unit) in dark text for a white
    background."""
    bar = simple.GetScalarBar(lut, view)
    bar.Title = title
    bar.ComponentTitle = ""
    bar.TitleColor = bar.LabelColor = [0.1, 0.1, 0.1]
    bar.TitleFontSize = bar.LabelFontSize = 18
    bar.AddRangeLabels = 0
    bar.WindowLocation = "Any Location"
    bar.Position = list(position)
    bar.ScalarBarLength = length
    bar.Visibility = 1
    return bar


def fetch_whole(proxy, port=0):
    """The output of `proxy` from every process, appended, on the client (pvpython, pvbatch or a
    client of pvserver). ParaView 5.11's servermanager.Fetch(proxy) brings only the first
    process's piece of a vtkUnstructuredGrid (it picks no append filter for it), hence the
    explicit reduction."""
    append = {"vtkPolyData": "vtkAppendPolyData"}.get(
        proxy.GetDataInformation(port).GetDataClassName(), "vtkAppendFilter")
    reducer = servermanager.filters.ReductionFilter(Input=simple.OutputPort(proxy, port),
                                                    PostGatherHelperName=append)
    data = servermanager.Fetch(reducer)
    simple.Delete(reducer)
    return data
