# SPDX-License-Identifier: BSD-3-Clause
"""Time of one Osteotomy update on the face's bones (pvpython): the first run (clip, cap, move)
and an edit of the move alone (the split is reused), medians of repeats.

    pvpython Benchmarks/osteotomy_edit_timing.py <FacePlan.so> [repeats]
"""
import statistics
import sys
import time

from paraview.simple import *

LoadPlugin(sys.argv[1], ns=globals())
repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 9
for name, origin, normal in (("maxilla", [80, 0, 113], [0, 0, -1]), ("mandible", [97, 0, 80], [-1, 0, 0])):
    reader = XMLPolyDataReader(FileName=["Data/face/%s.vtp" % name])
    reader.UpdatePipeline()
    first, edit = [], []
    for k in range(repeats):
        f = Osteotomy(Input=reader, Operation="Custom", Translation=[-5, 0, 0])
        f.CutPlane1.Origin, f.CutPlane1.Normal = origin, normal
        start = time.perf_counter()
        f.UpdatePipeline()
        first.append(time.perf_counter() - start)
        f.Translation = [-5 - 0.1 * (k + 1), 0, 0]
        start = time.perf_counter()
        f.UpdatePipeline()
        edit.append(time.perf_counter() - start)
        Delete(f)
    print("%s (%d points): first update %.1f ms, edit of the move %.1f ms (medians of %d)"
          % (name, reader.GetDataInformation().GetNumberOfPoints(), 1000 * statistics.median(first),
             1000 * statistics.median(edit), repeats))
