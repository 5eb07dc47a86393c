# SPDX-License-Identifier: BSD-3-Clause
"""Condensed FEM Deform's panel and display as a surgeon meets them (pvpython, headless):
- every settable property sits in one of the groups Material, Contact, Loads, Solver, Output,
  whose labels carry the units (Pa, mm); pvpython still names each property by its XML name;
  Method, Backend and ElementOrder are advanced;
- LiftOff is shown only with a large-deformation model (a visibility decorator on Model 1 and 2);
- no spreadsheet view is opened for the stage table (no View hint);
- Output Mode starts at Surface, and a new display is coloured by Displacement (its magnitude);
- the colour-by list offers the point arrays only: the field-data figures (Backend, Method,
  SolveTimeMs, ...) stay out of it, and pvpython still reads them by name;
- the stage table names this update's times: a reused stage reads 0 ms, its old time CachedTimeMs.
argv[1] is the plugin, argv[2] the Data folder.
"""
import os
import sys

from paraview import servermanager
from paraview.simple import *  # noqa: F401,F403

LoadPlugin(sys.argv[1], ns=globals())
data_dir = sys.argv[2]
from faceplan_test_util import check, fetch, finish  # noqa: E402

tissue = XMLUnstructuredGridReader(FileName=[os.path.join(data_dir, "face", "face_tissue.vtu")])
mandible = XMLPolyDataReader(FileName=[os.path.join(data_dir, "face", "mandible.vtp")])
roi = ROIExtract(Input=mandible)
cut = BezierCut(Input=roi)
fem = CondensedFEMDeform(Input=tissue, Bone=[cut])
sm = fem.SMProxy

# Groups, with the units in their labels: a property label with units would rename the property
# in pvpython (paraview.simple names it after its label).
GROUPS = {"Material": "(Pa)", "Contact": "(mm)", "Loads": "(kg/m^3, m/s^2)", "Solver": "", "Output": ""}
groups = {}
for g in range(sm.GetNumberOfPropertyGroups()):
    group = sm.GetPropertyGroup(g)
    groups[group.GetXMLLabel()] = [group.GetProperty(k).GetXMLName() for k in range(group.GetNumberOfProperties())]
expected = sorted((name + " " + units).strip() for name, units in GROUPS.items())
check(sorted(groups) == expected, "the panel's groups are %s (got %s)" % (expected, sorted(groups)))
settable = []
iterator = sm.NewPropertyIterator()
iterator.Begin()
while not iterator.IsAtEnd():
    prop = iterator.GetProperty()
    # A command property (vtkSMProperty itself: WaitForBackgroundWork) is no setting of the panel.
    if not prop.GetInformationOnly() and prop.GetClassName() not in ("vtkSMInputProperty", "vtkSMProperty"):
        settable.append(iterator.GetKey())
    iterator.Next()
for name in settable:
    owners = [g for g, members in groups.items() if name in members]
    check(len(owners) == 1, "%s is in exactly one group (%s)" % (name, owners))
    if name != "LengthUnit":  # labelled "Length Unit (m)" since its first release: LengthUnitm
        check(name in fem.ListProperties(), "pvpython names %s by its XML name" % name)
for name in ("Method", "Backend", "ElementOrder"):
    check(fem.GetProperty(name).SMProperty.GetPanelVisibility() == "advanced", "%s is advanced" % name)

# LiftOff's decorator: visible for Model NeoHookean (1) and Auto (2) only.
hints = fem.GetProperty("LiftOff").SMProperty.GetHints()
decorator = hints.FindNestedElementByName("PropertyWidgetDecorator") if hints else None
check(decorator is not None and decorator.GetAttribute("property") == "Model" and
      decorator.GetAttribute("mode") == "visibility" and
      sorted(decorator.GetAttribute("values").split()) == ["1", "2"],
      "LiftOff is shown only with a large-deformation model")

# No spreadsheet view per filter.
proxy_hints = sm.GetHints()
check(proxy_hints is not None and proxy_hints.FindNestedElementByName("View") is None,
      "no View hint: the stage table does not open a split view")

# Output and colouring.
check(fem.OutputMode == "Surface", "Output Mode starts at Surface (%s)" % fem.OutputMode)
fem.UpdatePipeline()
out = fetch(fem)
scalars = out.GetPointData().GetScalars()
check(scalars is not None and scalars.GetName() == "Displacement",
      "Displacement is the output's active scalars, which a new display is coloured by")
check(out.GetNumberOfCells() > 0 and all(out.GetCellType(c) == 5 for c in range(0, out.GetNumberOfCells(), 97)),
      "the default output is the boundary surface (triangles)")

# The colour-by list (the display's ColorArrayName domain, which the GUI's colour menu shows):
# point arrays only, while the field data stay readable with their names and values.
view = CreateView("RenderView")
display = Show(fem, view)
domain = display.GetProperty("ColorArrayName").SMProperty.FindDomain("vtkSMArrayListDomain")
listed = {(domain.GetString(i), domain.GetFieldAssociation(i)) for i in range(domain.GetNumberOfStrings())}
FIELD = 2  # vtkDataObject::FIELD_ASSOCIATION_NONE, as the domain names field data
field_names = [out.GetFieldData().GetArrayName(i) for i in range(out.GetFieldData().GetNumberOfArrays())]
check(("Displacement", 0) in listed, "Displacement is in the colour-by list: %s" % sorted(listed))
check(not [name for name, association in listed if association == FIELD],
      "no field-data array is in the colour-by list: %s" % sorted(listed))
check({"Backend", "Method", "SolveTimeMs", "Model"} <= set(field_names),
      "the field data are still there for scripts: %s" % field_names)
check(set(fem.FieldData.keys()) == set(field_names), "pvpython's FieldData lists them: %s" % fem.FieldData.keys())
Delete(display)
Delete(view)

# Stage table: this update's times.
cut.CurveU = [v + (0.5 if k % 3 == 2 else 0.0) for k, v in enumerate(cut.CurveU)]
cut.CurveV = [v + (0.5 if k % 3 == 2 else 0.0) for k, v in enumerate(cut.CurveV)]
fem.UpdatePipeline()
table = fetch(fem, 1)
names = [table.GetColumnName(c) for c in range(table.GetNumberOfColumns())]
check(names == ["Stage", "TimeMs", "Reused", "Backend", "CachedTimeMs"], "stage table columns %s" % names)
rows = [(table.GetValue(r, 0).ToString(), table.GetValue(r, 1).ToDouble(), table.GetValue(r, 2).ToInt(),
         table.GetValue(r, 4).ToDouble()) for r in range(table.GetNumberOfRows())]
reused = [r for r in rows if r[2] == 1]
check(reused and all(r[1] == 0.0 and r[3] > 0.0 for r in reused),
      "after an edit the reused stages read 0 ms now and keep their old time as CachedTimeMs: %s" % reused)

finish("TestCondensedFEMDeformPanel")
