# SPDX-License-Identifier: BSD-3-Clause
"""One client of the client-server test (pvpython): the face scene's pipeline in a builtin session
or on a pvserver, with the results brought back by servermanager.Fetch (GetClientSideObject() is
None on a client). With a server of several processes the tissue is split by RedistributeDataSet.

    pvpython ClientServerRun.py <builtin | host:port> <FacePlan.so> <Data dir> <work dir> <out.npz>
"""
import os
import sys

import numpy as np
from paraview import servermanager
from paraview.simple import Connect, LoadPlugin
from vtkmodules.util.numpy_support import vtk_to_numpy

url, plugin, data_dir, work_dir, out_file = sys.argv[1:6]
if url != "builtin":
    host, port = url.rsplit(":", 1)
    Connect(host, int(port))
LoadPlugin(plugin, remote=True)  # on the server (the same process when builtin)
LoadPlugin(plugin, remote=False)  # and on the client, for the proxies in paraview.simple
here = os.path.dirname(os.path.abspath(__file__))
sys.path[:0] = [here, os.path.join(here, "..", "..", "scripts")]
import faceplan_pipeline
import parallel_scenes

processes = servermanager.ActiveConnection.GetNumberOfDataPartitions()
split = "RedistributeDataSet" if processes > 1 else "none"
fem, _, edit = parallel_scenes.build("face", split, data_dir, work_dir)


def result():
    out = faceplan_pipeline.fetch_whole(fem)  # every piece, appended
    table = servermanager.Fetch(fem, 0, None, 1)  # the stage table of the first process
    pd = out.GetPointData()
    return {
        "ids": vtk_to_numpy(pd.GetArray(parallel_scenes.SERIAL_ID)).astype(np.int64),
        "displacement": vtk_to_numpy(pd.GetArray("Displacement")).copy(),
        "reused": np.array(out.GetFieldData().GetArray("PrecomputeReused").GetValue(0)),
        "stages": np.array([table.GetValue(r, 0).ToString() for r in range(table.GetNumberOfRows())]),
        "stage_reused": np.array([table.GetValue(r, 2).ToInt() for r in range(table.GetNumberOfRows())]),
    }


before = result()
edit()
after = result()
fem.UpdatePropertyInformation()
np.savez(out_file, processes=np.array(processes), precomputes=np.array(fem.GetPropertyValue("PrecomputeCount")),
         **{"before_" + k: v for k, v in before.items()}, **{"after_" + k: v for k, v in after.items()})
print("%s: %d server process(es), %d points, edit reused the precompute: %d"
      % (url, processes, len(before["ids"]), after["reused"]))
