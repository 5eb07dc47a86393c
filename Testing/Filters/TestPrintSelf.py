# SPDX-License-Identifier: BSD-3-Clause
"""PrintSelf of every FacePlan filter names each of its settable properties (pvpython, headless):
a proxy property (as the XML names it) that the class's PrintSelf leaves out is reported. Inputs,
information-only properties and the Region sub-proxy's own parameters are not printed by name.
argv[1] is the plugin.
"""
import sys

from paraview import servermanager
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
from faceplan_test_util import check, finish  # noqa: E402

surface = Sphere()
FILTERS = {"ROIExtract": dict(Input=surface), "BezierCut": dict(Input=surface),
           "CondensedFEMDeform": dict(Input=Tetrahedralize(Input=surface), Bone=surface)}
for name, inputs in FILTERS.items():
    proxy = globals()[name](**inputs)
    printed = str(proxy.GetClientSideObject())
    settable = []
    for prop in proxy.ListProperties():
        sm = proxy.GetProperty(prop).SMProperty
        # A command property (vtkSMProperty itself: WaitForBackgroundWork) holds no value to print.
        if sm.GetInformationOnly() or isinstance(proxy.GetProperty(prop), servermanager.InputProperty) or \
                sm.GetClassName() == "vtkSMProperty":
            continue
        settable.append(sm.GetXMLName() if hasattr(sm, "GetXMLName") else prop)
    missing = [p for p in settable if p + ":" not in printed]
    print("%s: %d settable properties, PrintSelf misses %s" % (name, len(settable), missing))
    check(not missing, "%s's PrintSelf names every property (missing %s)" % (name, missing))
    Delete(proxy)

finish("TestPrintSelf")
