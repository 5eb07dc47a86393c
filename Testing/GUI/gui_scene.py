# SPDX-License-Identifier: BSD-3-Clause
"""The face scene's display in the GUI's render view, shared by the GUI test scripts that show the
three-filter pipeline (faceplan_pipeline.build): the deformed tissue translucent and coloured by
Displacement on a fixed 0-6 mm scale, the cut bone on the same scale, the operative surface in
blue, and the camera on the chin."""


def show_pipeline(simple, fem, cut):
    """Shows fem's and cut's outputs in the active render view; returns the view (None if the GUI
    has none)."""
    view = simple.GetActiveViewOrCreate("RenderView")
    if view is None:
        return None
    face = simple.Show(simple.OutputPort(fem, 0), view)
    simple.ColorBy(face, ("POINTS", "Displacement", "Magnitude"))
    face.Opacity = 0.3
    lut = simple.GetColorTransferFunction("Displacement")
    lut.ApplyPreset("Turbo", True)
    lut.AutomaticRescaleRangeMode = "Never"
    lut.RescaleTransferFunction(0.0, 6.0)
    bone = simple.Show(simple.OutputPort(cut, 0), view)
    simple.ColorBy(bone, ("POINTS", "Displacement", "Magnitude"))
    bone.LookupTable = lut
    surface = simple.Show(simple.OutputPort(cut, 1), view)
    surface.ColorArrayName = ["POINTS", ""]
    surface.AmbientColor = surface.DiffuseColor = [0.2, 0.5, 0.9]
    surface.Opacity = 0.5
    bone.SetScalarBarVisibility(view, True)
    lut.RescaleTransferFunction(0.0, 6.0)  # ColorBy rescales to the data: back to the fixed scale
    simple.Render(view)
    view.CameraFocalPoint = [85.0, 0.0, 92.0]
    view.CameraPosition = [-260.0, -250.0, 10.0]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    simple.Render(view)
    return view
