# SPDX-License-Identifier: BSD-3-Clause
"""The three osteotomy scenes on the Badin face, shared by the demo (osteotomy_demo.py), the GUI test
and the README's screenshot. Lengths in mm; the face looks towards -x (anterior), z is up."""
from paraview import simple

# name: (bone file, Osteotomy's Operation preset, translation, what it is). The preset places the
# cut planes from the bone's geometry and marks the operation's standard approach on the moved bone
# (point arrays Released: the degloved bone; Sliding: the teeth), so a scene is what a user gets
# from the filter's defaults plus a move (Core/Osteotomy/OperationPresets.h).
SCENES = {
    "lefort1": ("maxilla", "LeFortI", [-5.0, 0.0, 0.0],
                "Le Fort I advancement of 5 mm: the maxilla below a horizontal cut above the nasal spine"),
    "bsso": ("mandible", "BSSO", [-6.0, 0.0, 0.0],
             "BSSO advancement of 6 mm: the mandible's body in front of a cut through both rami"),
    "genioplasty": ("mandible", "Genioplasty", [-5.0, 0.0, 0.0],
                    "genioplasty advancement of 5 mm: the chin below a horizontal cut and in front of a "
                    "coronal one"),
}


# Closed lips: with an Osteotomy preset's bone, CondensedFEMDeform's LipSeal (Auto) ties facing lip
# surfaces up to 3 mm apart, the interlabial gap of competent lips at rest. The Badin face is meshed
# with the jaw open (the incisal edges 4.4 mm apart vertically) and the lips 0.6-2.4 mm apart across
# the oral fissure; in occlusion, where plans are made and the clinical studies' cephalograms are
# taken, these lips are closed (docs/CLINICAL.md, section 5).
OPERATION_LIP_SEAL = 3.0


# The model a user gets for an operation is CondensedFEMDeform's defaults with an Osteotomy preset's
# bone, so the scenes set nothing on the filter: ContactModel Auto takes the preset's Sliding array
# (the teeth), the preset's Released array frees the degloved bone's tissue, LiftOff (on) lets the
# lips leave the teeth, LipSeal Auto closes the lips, and Model Auto solves for large deformations
# where the linear result strains beyond 10 %. What the defaults give, for printed summaries:
OPERATION_MODEL = ["ContactModel=Auto (ByArray: Sliding on the teeth)", "Released where degloved",
                   "LiftOff (lips may leave the teeth)",
                   "LipSeal=Auto (%g mm: closed lips)" % OPERATION_LIP_SEAL,
                   "Model=Auto (NeoHookean beyond 10 % strain)"]


def configure_model(fem):
    """The large-deformation model set explicitly, for the benchmarks that time it alone: a 5-6 mm
    rigid move strains the tissue at the corners of the mouth and the segment's edges by tens of
    percent (docs/OSTEOTOMY-STRAIN.md), so Model Auto picks NeoHookean for these plans anyway, after
    a linear solve that this skips. Returns what was set, for the printed summary."""
    fem.Model = "NeoHookean"
    return ["Model=NeoHookean (large deformation)"]


# The arrays an Osteotomy output carries, all zero: a bone that stays where it is, its tissue tied
# (no Released, no Sliding). Append Geometry keeps only the point arrays every input has, so the
# fixed bones need them too.
_UNMOVED = """
import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk
out = self.GetOutput()
out.ShallowCopy(self.GetInput())
n = out.GetNumberOfPoints()
for name, values in (("Displacement", np.zeros((n, 3))), ("ROIMask", np.zeros(n, np.uint8)),
                     ("SegmentId", np.zeros(n, np.int32)), ("Released", np.zeros(n, np.uint8)),
                     ("Sliding", np.zeros(n, np.uint8))):
    a = numpy_to_vtk(values, deep=1)
    a.SetName(name)
    out.GetPointData().AddArray(a)
"""


def unmoved(bone):
    """The bone with zero Displacement, ROIMask and SegmentId, to append beside an Osteotomy."""
    return simple.ProgrammableFilter(Input=bone, Script=_UNMOVED, OutputDataSetType="vtkPolyData")


def build(data_dir, scene, translation=None, rotation=None):
    """Returns (tissue, bone reader, osteotomy, skeleton, fem) proxies for a scene; LoadPlugin must
    have run first. The osteotomy is the scene's Operation preset with the scene's move (or
    `translation` and `rotation`, degrees, for a sweep). The soft tissue is tied to all three bones:
    the operated one (Osteotomy's output, with the preset's Released and Sliding arrays) and the
    others, which stay put (appended with Append Geometry)."""
    bone_name, operation, scene_translation, _ = SCENES[scene]
    tissue = simple.XMLUnstructuredGridReader(registrationName="face_tissue.vtu",
                                              FileName=[data_dir + "/face/face_tissue.vtu"])
    bone = simple.XMLPolyDataReader(registrationName=bone_name + ".vtp",
                                    FileName=[data_dir + "/face/%s.vtp" % bone_name])
    others = [simple.XMLPolyDataReader(registrationName=name + ".vtp", FileName=[data_dir + "/face/%s.vtp" % name])
              for name in ("maxilla", "mandible", "cranium") if name != bone_name]
    osteotomy = simple.Osteotomy(registrationName="Osteotomy", Input=bone, Operation=operation)
    osteotomy.Translation = list(translation if translation is not None else scene_translation)
    if rotation is not None:
        osteotomy.Rotation = list(rotation)
    skeleton = simple.AppendGeometry(registrationName="Skeleton",
                                     Input=[osteotomy] + [unmoved(other) for other in others])
    fem = simple.CondensedFEMDeform(registrationName="CondensedFEMDeform", Input=tissue, Bone=skeleton)
    fem.ContactDistance = 1.0
    return tissue, bone, osteotomy, skeleton, fem
