# SPDX-License-Identifier: BSD-3-Clause
"""TissueModelFromCT under `mpiexec -n 2 pvbatch` meshes the whole CT once, on rank 0: the model
equals the serial one point for point, and no other rank adds a copy or a slab's model.
Exits 77 (CTest SKIP_RETURN_CODE) when mpiexec is missing.

    pvpython TestParallelTissueModel.py <pvbatch> <FacePlan.so> <CT .vti> <work dir>
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mpi_test_util as util

pvbatch, plugin, ct_file, work_dir = sys.argv[1:5]
mpiexec = util.prepare(work_dir)
script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "RunTissueModel.py")
results = {}
for label, prefix in (("serial", []), ("n2", mpiexec + ["-n", "2"])):
    out = os.path.join(work_dir, label + ".npz")
    log = util.run(prefix + [pvbatch, script, plugin, ct_file, out])
    util.check("ERR|" not in log, "%s: no error logged" % label)
    if util.check(os.path.exists(out), "%s: results written" % label):
        results[label] = np.load(out)
if len(results) == 2:
    serial, n2 = results["serial"], results["n2"]
    util.check(np.array_equal(serial["points"], n2["points"]), "the MPI model's points equal the serial ones")
    util.check(serial["cells"] == n2["cells"], "the MPI model has the serial cell count")
    util.check(n2["total_points"] == len(serial["points"]), "no rank but the first holds model points")
util.finish("TestParallelTissueModel")
