# SPDX-License-Identifier: BSD-3-Clause
"""Contract checks shared by the pvpython tests: a failed check is recorded and the test goes on,
then `finish` exits non-zero. No ParaView import, so that drivers that must not initialise
ParaView at load time (the MPI ones) can use it too."""
import sys

failures = []


def check(cond, what):
    """Records a failed contract check (the test keeps going, then exits non-zero)."""
    if not cond:
        failures.append(what)
        print("FAIL:", what)
    return bool(cond)


def finish(name):
    if failures:
        print("%s: %d check(s) failed" % (name, len(failures)))
        sys.exit(1)
    print("%s: all checks passed" % name)
    sys.exit(0)
