# SPDX-License-Identifier: BSD-3-Clause
"""The render view FacePlan's figures are drawn in, shared by the demo scripts, the overview and
the image tests: a white background (the figures go on white pages; ParaView >= 5.10 takes the
background from its colour palette unless told not to), no orientation axes, and screenshots at the
view's own size."""
import os

from paraview.simple import CreateRenderView, SaveScreenshot


def white_render_view(size=None):
    view = CreateRenderView()
    if size:
        view.ViewSize = list(size)
    view.OrientationAxesVisibility = 0
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:  # ParaView < 5.10 has no palette switch
        pass
    view.Background = [1.0, 1.0, 1.0]
    return view


def screenshot(view, out_dir, name, size):
    """Saves `view` as out_dir/name at `size` pixels; returns the path."""
    path = os.path.join(out_dir, name)
    SaveScreenshot(path, view, ImageResolution=list(size))
    return path
