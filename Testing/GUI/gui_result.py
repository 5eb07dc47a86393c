# SPDX-License-Identifier: BSD-3-Clause
"""The result a GUI test script reports to run_gui_test.py: its checks, failures, error and info,
written as JSON to $FACEPLAN_GUI_RESULT. The GUI's exit code does not reflect Python errors, hence
the file. Shared by the scripts that run inside ParaView's GUI (TestGUI*.py)."""
import json
import os

result = {"checks": [], "failures": [], "error": None, "info": {}}


def check(cond, what):
    result["checks"].append(what)
    if not cond:
        result["failures"].append(what)
    return bool(cond)


def watch_messages():
    """The warnings and errors the session says from now on: a list filled by observers on the
    GUI's vtkOutputWindow, which fires WarningEvent / ErrorEvent after showing the text (the GUI
    pops its Output Messages window at each), so observing it hides none. Also records the output
    window's class in result["info"]."""
    from vtkmodules.vtkCommonCore import vtkOutputWindow

    said = []
    output_window = vtkOutputWindow.GetInstance()
    for event in ("WarningEvent", "ErrorEvent"):
        output_window.AddObserver(event, lambda obj, name: said.append(name))
    result["info"]["output_window"] = output_window.GetClassName()
    return said


def write_result():
    path = os.environ.get("FACEPLAN_GUI_RESULT", "faceplan_gui_result.json")
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(result, f, indent=1)
    os.replace(tmp, path)  # the wrapper polls for the file: never let it see half of it
