# SPDX-License-Identifier: BSD-3-Clause
"""Shared by the MPI and client-server test drivers (pvpython): finding mpiexec, running a command
with its output captured, and recording checks."""
import os
import shutil
import subprocess
import sys

SKIP = 77  # the tests' SKIP_RETURN_CODE, as in Testing/Images
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "Filters"))
from faceplan_checks import check, failures, finish  # noqa: E402,F401 (re-exported to the drivers)


def mpiexec_or_skip():
    """mpiexec with the options CI needs (more ranks than cores; root in containers), or SKIP."""
    exe = shutil.which("mpiexec")
    if not exe:
        print("SKIPPED: mpiexec not found")
        sys.exit(SKIP)
    version = subprocess.run([exe, "--version"], capture_output=True, text=True).stdout
    cmd = [exe]
    if "Open MPI" in version or "OpenRTE" in version:
        cmd.append("--oversubscribe")
        if os.geteuid() == 0:
            cmd.append("--allow-run-as-root")
    return cmd


def prepare(work_dir):
    """mpiexec (or SKIP, see mpiexec_or_skip) and an empty work_dir: what every driver starts with."""
    mpiexec = mpiexec_or_skip()
    shutil.rmtree(work_dir, ignore_errors=True)
    os.makedirs(work_dir)
    return mpiexec


def clean_environment():
    """This process's environment without the MPI runtime's variables: pvpython initialises MPI
    as a singleton, and an mpiexec (or pvserver) started with them fails at once."""
    return {k: v for k, v in os.environ.items()
            if not k.startswith(("OMPI_", "PMIX_", "OPAL_", "HYDRA_", "PMI_"))}


def run(cmd, timeout=600):
    """Runs cmd, prints and returns its output; a non-zero exit is a failed check."""
    print("$", " ".join(cmd), flush=True)
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=timeout, env=clean_environment())
    print(proc.stdout if proc.returncode else proc.stdout[-4000:])
    check(proc.returncode == 0, "%s exited with %d" % (os.path.basename(cmd[0]), proc.returncode))
    return proc.stdout
