"""The three osteotomy scenes on the Badin face, shared by the demo (osteotomy_demo.py), the GUI test
and the README's screenshot. Lengths in mm; the face looks towards -x (anterior), z is up."""
from paraview import simple

# name: (bone file, cut planes [(origin, normal)], translation, what it is)
SCENES = {
    "lefort1": ("maxilla", [([80.0, 0.0, 113.0], [0.0, 0.0, -1.0])], [-5.0, 0.0, 0.0],
                "Le Fort I advancement of 5 mm: the maxilla below a horizontal cut above the tooth roots"),
    "bsso": ("mandible", [([97.0, 0.0, 80.0], [-1.0, 0.0, 0.0])], [-6.0, 0.0, 0.0],
             "BSSO advancement of 6 mm: the mandible's body in front of a cut through both rami"),
    "genioplasty": ("mandible", [([70.0, 0.0, 68.0], [0.0, 0.0, -1.0]), ([82.0, 0.0, 60.0], [-1.0, 0.0, 0.0])],
                    [-5.0, 0.0, 0.0],
                    "genioplasty advancement of 5 mm: the chin below a horizontal cut and in front of a "
                    "coronal one"),
}


def configure_contact(fem):
    """Tissue contact that matches the operation, where the plugin offers it: the soft tissue slides
    over the bone (lips over teeth) and is released within 5 mm of the cut, where the surgeon
    detaches it. A larger ReleaseDistance is no better model: it also frees the tissue on the
    segment (the unoperated bones count as another region, and the teeth of both jaws lie within
    10 mm of each other), so that the tissue stops following the move. These settings still exceed
    the small-strain limit; docs/OSTEOTOMY-STRAIN.md says why. Returns what was set, for the printed
    summary."""
    chosen = []
    props = fem.ListProperties()
    if "ContactModel" in props:
        try:
            fem.ContactModel = "Sliding"
            chosen.append("ContactModel=Sliding")
        except (ValueError, AttributeError):
            pass
    if "ReleaseDistance" in props:
        fem.ReleaseDistance = 5.0
        chosen.append("ReleaseDistance=5 mm")
    return chosen or ["tied contact (ContactModel/ReleaseDistance not available)"]


# The arrays an Osteotomy output carries, all zero: a bone that stays where it is. Append Geometry
# keeps only the point arrays every input has, so the fixed bones need them too.
_UNMOVED = """
import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk
out = self.GetOutput()
out.ShallowCopy(self.GetInput())
n = out.GetNumberOfPoints()
for name, values in (("Displacement", np.zeros((n, 3))), ("ROIMask", np.zeros(n, np.uint8)),
                     ("SegmentId", np.zeros(n, np.int32))):
    a = numpy_to_vtk(values, deep=1)
    a.SetName(name)
    out.GetPointData().AddArray(a)
"""


def unmoved(bone):
    """The bone with zero Displacement, ROIMask and SegmentId, to append beside an Osteotomy."""
    return simple.ProgrammableFilter(Input=bone, Script=_UNMOVED, OutputDataSetType="vtkPolyData")


def build(data_dir, scene):
    """Returns (tissue, bone reader, osteotomy, skeleton, fem) proxies for a scene; LoadPlugin must have run
    first. The soft tissue is tied to all three bones: the operated one (Osteotomy's output) and
    the others, which stay put (appended with Append Geometry)."""
    bone_name, planes, translation, _ = SCENES[scene]
    tissue = simple.XMLUnstructuredGridReader(registrationName="face_tissue.vtu",
                                              FileName=[data_dir + "/face/face_tissue.vtu"])
    bone = simple.XMLPolyDataReader(registrationName=bone_name + ".vtp",
                                    FileName=[data_dir + "/face/%s.vtp" % bone_name])
    others = [simple.XMLPolyDataReader(registrationName=name + ".vtp", FileName=[data_dir + "/face/%s.vtp" % name])
              for name in ("maxilla", "mandible", "cranium") if name != bone_name]
    osteotomy = simple.Osteotomy(registrationName="Osteotomy", Input=bone)
    osteotomy.CutPlane1.Origin, osteotomy.CutPlane1.Normal = planes[0]
    if len(planes) > 1:
        osteotomy.UseSecondPlane = 1
        osteotomy.CutPlane2.Origin, osteotomy.CutPlane2.Normal = planes[1]
    osteotomy.Translation = translation
    skeleton = simple.AppendGeometry(registrationName="Skeleton",
                                     Input=[osteotomy] + [unmoved(other) for other in others])
    fem = simple.CondensedFEMDeform(registrationName="CondensedFEMDeform", Input=tissue, Bone=skeleton)
    fem.ContactDistance = 1.0
    return tissue, bone, osteotomy, skeleton, fem
