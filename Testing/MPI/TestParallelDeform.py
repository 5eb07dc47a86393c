# SPDX-License-Identifier: BSD-3-Clause
"""CondensedFEMDeform (with ROIExtract and BezierCut, or Osteotomy, upstream) under MPI matches
the serial run.

Runs RunParallelDeform.py once with serial pvbatch, then under `mpiexec -n N pvbatch` for each N,
with the tissue split by RedistributeDataSet, D3 and a 2-piece .pvtu (and a BSSO osteotomy scene,
tissue and bone split by RedistributeDataSet). Compares every process's piece of the output (and
of BezierCut's output on the face, and the sphere's Surface output) with the serial result by
serial point id: max |dDisplacement| relative to the serial max |Displacement| <= 1e-10, before
and after an edit. Checks that the edit reused the precompute on the solving rank, that every
piece carries the same field data, and that each real error is logged exactly once and no other
error at all (empty pieces log nothing). Exits 77 (CTest SKIP_RETURN_CODE) when mpiexec is
missing.

    pvpython TestParallelDeform.py <pvbatch> <FacePlan.so> <Data dir> <work dir> <N>...
"""
import glob
import json
import os
import subprocess
import sys

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLGenericDataObjectReader

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mpi_test_util as util

pvbatch, plugin, data_dir, work_dir = sys.argv[1:5]
ranks = [int(n) for n in sys.argv[5:]]
SPLITS = ["RedistributeDataSet", "D3", "pvtu"]
SCENES = ["face", "sphere"]
TOLERANCE = 1e-10
EXPECTED_ERRORS = ["YoungsModulus must be a positive number", "apply ROI Extract first",
                   "ContactModel ByArray needs a bone point array named Sliding"]

mpiexec = util.prepare(work_dir)
script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "RunParallelDeform.py")


def run(label, prefix, splits):
    log = util.run(prefix + [pvbatch, script, plugin, data_dir, work_dir, label] + splits)
    errors = [line for line in log.splitlines() if "ERR|" in line or "ERROR:" in line]
    for expected in EXPECTED_ERRORS:
        n = sum(expected in line for line in errors)
        util.check(n == 1, "%s: '%s' logged %d times (once expected)" % (label, expected, n))
    unexpected = [l for l in errors if not any(e in l for e in EXPECTED_ERRORS)]
    util.check(not unexpected, "%s: unexpected errors: %s" % (label, unexpected[:3]))


def pieces(label, key):
    files = sorted(glob.glob(os.path.join(work_dir, label, key, key + "_*.vt[up]")))
    out = []
    for name in files:
        reader = vtkXMLGenericDataObjectReader()
        reader.SetFileName(name)
        reader.Update()
        out.append(reader.GetOutput())
    return out


def field_values(piece):
    fd = piece.GetFieldData()
    values = {}
    for i in range(fd.GetNumberOfArrays()):
        a = fd.GetAbstractArray(i)
        values[a.GetName()] = a.GetVariantValue(0).ToString()
    return values


def displacement_by_id(grids):
    ids = np.concatenate([vtk_to_numpy(g.GetPointData().GetArray("SerialPointId")) for g in grids
                          if g.GetNumberOfPoints()])
    u = np.concatenate([vtk_to_numpy(g.GetPointData().GetArray("Displacement")) for g in grids
                        if g.GetNumberOfPoints()])
    return ids.astype(np.int64), u


run("serial", [], ["none"])
for n in ranks:
    run("n%d" % n, mpiexec + ["-n", str(n)], SPLITS)

# The results: the tissue of both scenes before and after the edit, the face's cut bone
# (BezierCut's output) and the sphere's Surface output.
results = [(scene, phase) for scene in SCENES for phase in ("before", "after")]
results += [("face", "before_bone"), ("face", "after_bone"), ("sphere", "surface")]
results += [("osteotomy", "before"), ("osteotomy", "after")]
for scene, tag in results:
    serial = pieces("serial", "%s_none_%s" % (scene, tag))
    ref_ids, ref_u = displacement_by_id(serial)
    reference = np.full((ref_ids.max() + 1, 3), np.nan)
    reference[ref_ids] = ref_u
    scale = np.abs(ref_u).max()
    for n in ranks:
        precomputes = json.load(open(os.path.join(work_dir, "n%d" % n, "precomputes.json")))
        for split in SPLITS if scene != "osteotomy" else ["RedistributeDataSet"]:
            key = "%s_%s_%s" % (scene, split, tag)
            grids = pieces("n%d" % n, key)
            # The writer skips empty pieces: a 2-piece tissue file, a 1-piece bone file.
            nonempty = n if split != "pvtu" else (1 if tag.endswith("bone") else min(n, 2))
            if not util.check(len(grids) == nonempty, "n%d %s: %d pieces written" % (n, key, len(grids))):
                continue
            ids, u = displacement_by_id(grids)
            covered = np.zeros(len(reference), bool)
            covered[ids] = True
            util.check(covered[ref_ids].all(), "n%d %s: every serial point is in a piece" % (n, key))
            diff = np.abs(u - reference[ids]).max() / scale
            util.check(diff <= TOLERANCE, "n%d %s: max |dDisplacement| %.2e relative (<= %.0e)"
                       % (n, key, diff, TOLERANCE))
            print("n%d %s: %d pieces, max |dDisplacement| %.2e relative" % (n, key, len(grids), diff))
            fields = [field_values(g) for g in grids]
            util.check(all(f == fields[0] for f in fields), "n%d %s: same field data on every rank" % (n, key))
            if tag == "surface":
                cells = sum(g.GetNumberOfCells() for g in grids)
                util.check(cells == sum(g.GetNumberOfCells() for g in serial),
                           "n%d %s: the pieces hold each boundary triangle once" % (n, key))
            if tag == "after":
                util.check(fields[0].get("PrecomputeReused") == "1",
                           "n%d %s: the edit reused the precompute" % (n, key))
                util.check(precomputes["%s_%s" % (scene, split)] == 1,
                           "n%d %s: one precompute on the solving rank" % (n, key))
# A failure on the solving rank is every rank's: no process keeps (or invents) a result.
for label in ["serial"] + ["n%d" % n for n in ranks]:
    grids = pieces(label, "byarray")
    held = sum(g.GetNumberOfPoints() for g in grids)
    util.check(held == 0, "%s: ByArray without Sliding leaves every piece empty (%d points)" % (label, held))
util.finish("TestParallelDeform")
