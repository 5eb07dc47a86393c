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


# Where each operation detaches the soft tissue from the bone it cuts: the surgeon degloves the bone
# around the osteotomy through a vestibular incision, and the tissue there no longer follows the
# bone. A box in the bone's coordinates (x, z ranges in mm; y unbounded) and which side of the cut
# it covers ("fixed": the bone that stays, "both": the segment too). The regions are a matter of the
# surgical approach, not of the cut's geometry, so the scene marks them (bone point array Released)
# rather than the Osteotomy filter from its planes.
#   Le Fort I: the maxilla above the cut, up to the infraorbital rim and back to the buttress.
#   BSSO: the mandible's body and ramus either side of the split, where the lateral cortex is
#         exposed.
#   genioplasty: the anterior mandible above the chin cut, up to the tooth roots.
DETACHED = {
    "lefort1": dict(x=(-1e9, 1e9), z=(-1e9, 135.0), side="fixed"),
    "bsso": dict(x=(85.0, 110.0), z=(-1e9, 1e9), side="both"),
    "genioplasty": dict(x=(-1e9, 90.0), z=(-1e9, 85.0), side="fixed"),
}
# The teeth of both jaws, where lips and cheeks rest on the bone and slide over it (bone point array
# Sliding, ContactModel ByArray): the band of the occlusal plane in front of the molars.
TEETH = dict(x=(-1e9, 80.0), z=(88.0, 110.0))


def configure_contact(fem):
    """Tissue contact that matches the operation: tied to bone (the segment carries its tissue
    along), free where the surgeon detached it (the bones' Released arrays, set by `build`) and
    sliding over the teeth (ContactModel ByArray with the bones' Sliding arrays). Returns what was
    set, for the printed summary."""
    fem.ContactModel = "ByArray"
    fem.ReleaseDistance = 0.0
    return ["ContactModel=ByArray (Sliding on the teeth)", "Released where degloved"]


def configure_model(fem):
    """The model for a plan's result: a 5-6 mm rigid move strains the tissue at the corners of the
    mouth and the segment's edges by tens of percent (docs/OSTEOTOMY-STRAIN.md), beyond the linear
    model's small-strain range, so the demos solve for large deformations (Model NeoHookean, with
    the same small-strain moduli) and let the lips leave the teeth where they are pulled away
    (LiftOff). Interactive editing keeps the linear model (the GUI test, the latency benchmark).
    Returns what was set, for the printed summary."""
    fem.Model = "NeoHookean"
    fem.LiftOff = 1
    return ["Model=NeoHookean (large deformation)", "LiftOff (lips may leave the teeth)"]


def _box_expression(box):
    """A Calculator expression, 1 inside the box and 0 outside; unbounded sides are left out."""
    terms = []
    for axis, (low, high) in (("X", box["x"]), ("Z", box["z"])):
        if low > -1e9:
            terms.append("(coords%s>=%r)" % (axis, low))
        if high < 1e9:
            terms.append("(coords%s<=%r)" % (axis, high))
    return "*".join(terms) or "1"


def contact_flags(bone, detached=None):
    """The bone (before any move) with point arrays Released (1 inside the `detached` box, see
    DETACHED; both sides of the cut) and Sliding (1 on the teeth), both uint8. The Osteotomy filter
    carries them onto its output, so nothing is recomputed when the segment moves."""
    out = bone
    for name, expression in (("Released", _box_expression(detached) if detached else "0"),
                             ("Sliding", _box_expression(TEETH))):
        out = simple.Calculator(Input=out, Function=expression, ResultArrayName=name,
                                ResultArrayType="Unsigned Char")
    return out


def fixed_side_only(osteotomy):
    """Released kept where the bone stays (ROIMask 0) only. The points the cut adds take the flag
    interpolated from both sides, so the side is decided after the cut, on every move."""
    # FunctionParserType 0 (vtkFunctionParser) runs about 3 times faster than ExprTk here.
    return simple.Calculator(Input=osteotomy, Function="Released*(1-ROIMask)", FunctionParserType=0,
                             ResultArrayName="Released", ResultArrayType="Unsigned Char")


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
    the others, which stay put (appended with Append Geometry), each with its Released and Sliding
    arrays (contact_flags)."""
    bone_name, planes, translation, _ = SCENES[scene]
    tissue = simple.XMLUnstructuredGridReader(registrationName="face_tissue.vtu",
                                              FileName=[data_dir + "/face/face_tissue.vtu"])
    bone = simple.XMLPolyDataReader(registrationName=bone_name + ".vtp",
                                    FileName=[data_dir + "/face/%s.vtp" % bone_name])
    others = [simple.XMLPolyDataReader(registrationName=name + ".vtp", FileName=[data_dir + "/face/%s.vtp" % name])
              for name in ("maxilla", "mandible", "cranium") if name != bone_name]
    osteotomy = simple.Osteotomy(registrationName="Osteotomy", Input=contact_flags(bone, DETACHED[scene]))
    osteotomy.CutPlane1.Origin, osteotomy.CutPlane1.Normal = planes[0]
    if len(planes) > 1:
        osteotomy.UseSecondPlane = 1
        osteotomy.CutPlane2.Origin, osteotomy.CutPlane2.Normal = planes[1]
    osteotomy.Translation = translation
    skeleton = simple.AppendGeometry(registrationName="Skeleton",
                                     Input=[fixed_side_only(osteotomy) if DETACHED[scene]["side"] == "fixed"
                                            else osteotomy] + [unmoved(contact_flags(other)) for other in others])
    fem = simple.CondensedFEMDeform(registrationName="CondensedFEMDeform", Input=tissue, Bone=skeleton)
    fem.ContactDistance = 1.0
    return tissue, bone, osteotomy, skeleton, fem
