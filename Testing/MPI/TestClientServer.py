# SPDX-License-Identifier: BSD-3-Clause
"""The face scene through a pvserver gives the builtin session's results.

Runs ClientServerRun.py builtin, then against `pvserver` on loopback (results bit-identical to
builtin, table included) and against `mpiexec -n 2 pvserver` (tissue split by
RedistributeDataSet; max |dDisplacement| <= 1e-10 relative to builtin). In each, an edit of the
cut re-solves with the precompute reused. Exits 77 (CTest SKIP_RETURN_CODE) when mpiexec is
missing.

    pvpython TestClientServer.py <pvserver> <FacePlan.so> <Data dir> <work dir>
"""
import os
import socket
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mpi_test_util as util

pvserver, plugin, data_dir, work_dir = sys.argv[1:5]
mpiexec = util.prepare(work_dir)
client = os.path.join(os.path.dirname(os.path.abspath(__file__)), "ClientServerRun.py")
pvpython = sys.executable if os.path.basename(sys.executable).startswith("pvpython") else "pvpython"


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run_client(url, name):
    out = os.path.join(work_dir, name + ".npz")
    util.run([pvpython, client, url, plugin, data_dir, work_dir, out])
    return np.load(out) if os.path.exists(out) else None


def with_server(prefix, name):
    """Starts pvserver (under `prefix`), runs a client against it, stops the server if needed."""
    port = free_port()
    cmd = prefix + [pvserver, "--server-port=%d" % port]
    print("$", " ".join(cmd), flush=True)
    server = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                              env=util.clean_environment())
    deadline = time.time() + 120
    for line in server.stdout:
        print("server:", line.rstrip())
        if "Accepting connection" in line or time.time() > deadline:
            break
    try:
        return run_client("localhost:%d" % port, name)
    finally:
        try:
            server.wait(timeout=60)  # a pvserver exits when its client disconnects
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait()


def check_edit(r, name):
    util.check(r["after_reused"] == 1, "%s: the edit reused the precompute" % name)
    util.check(r["precomputes"] == 1, "%s: one precompute" % name)


builtin = run_client("builtin", "builtin")
single = with_server([], "pvserver")
parallel = with_server(mpiexec + ["-n", "2"], "pvserver_n2")
if builtin is None or single is None or parallel is None:
    util.check(False, "every client wrote its results")
    util.finish("TestClientServer")

check_edit(builtin, "builtin")
check_edit(single, "pvserver")
check_edit(parallel, "mpiexec -n 2 pvserver")
util.check(parallel["processes"] == 2, "the MPI server has 2 processes")
for phase in ("before", "after"):
    same = (np.array_equal(builtin[phase + "_ids"], single[phase + "_ids"])
            and np.array_equal(builtin[phase + "_displacement"], single[phase + "_displacement"]))
    util.check(same, "pvserver %s: Displacement bit-identical to builtin" % phase)
    for column in ("stages", "stage_reused"):
        util.check(np.array_equal(builtin[phase + "_" + column], single[phase + "_" + column]),
                   "pvserver %s: stage table column %s as builtin" % (phase, column))
    reference = np.full((builtin[phase + "_ids"].max() + 1, 3), np.nan)
    reference[builtin[phase + "_ids"]] = builtin[phase + "_displacement"]
    ids = parallel[phase + "_ids"]
    diff = np.abs(parallel[phase + "_displacement"] - reference[ids]).max() / np.abs(
        builtin[phase + "_displacement"]).max()
    covered = np.zeros(len(reference), bool)
    covered[ids] = True
    util.check(covered[builtin[phase + "_ids"]].all(), "mpiexec -n 2 pvserver %s: every point fetched" % phase)
    util.check(diff <= 1e-10, "mpiexec -n 2 pvserver %s: max |dDisplacement| %.2e relative" % (phase, diff))
    print("mpiexec -n 2 pvserver %s: max |dDisplacement| %.2e relative to builtin" % (phase, diff))
util.finish("TestClientServer")
