# SPDX-License-Identifier: BSD-3-Clause
"""Races between edits and the background precompute (docs/RELIABILITY.md, section 4).

CondensedFEMDeform's RequestData waits on the pipeline thread for its worker's precompute and fires
progress events every 20 ms meanwhile; those events are where a session can act while a precompute
runs, so every action below happens in a progress callback:
  edits: cut edits on a 10 ms grid (each callback applies the edits whose 10 ms slots have passed)
         during a precompute of >= 2 s, and one ROI change 1 s into it; the output after the
         next update must equal a fresh pipeline's on the final inputs (<= 1e-12) and come from a
         new precompute (the ROI changed), not from the superseded request;
  delete: the filter's proxy is deleted 0.2 s into a (linear) precompute (child process: it must end,
         exit 0, within the time limit);
  exit:   pvpython exits (sys.exit) 0.2 s into a (linear) precompute (child process, the same).
  pvpython --force-offscreen-rendering scripts/soak_race.py --plugin <FacePlan.so> --data <Data>
"""
import argparse
import math
import os
import subprocess
import sys
import time

import numpy as np
from paraview import simple
from paraview import servermanager
from vtkmodules.util.numpy_support import vtk_to_numpy

parser = argparse.ArgumentParser()
parser.add_argument("--plugin", required=True)
parser.add_argument("--data", required=True)
# Quadratic by default: the face's linear precompute can end within the 2 s race window on a fast
# machine; the quadratic one lasts several seconds on any machine.
parser.add_argument("--element-order", type=int, default=1, help="CondensedFEMDeform ElementOrder of the edits case")
parser.add_argument("--child", choices=("delete", "exit"))
parser.add_argument("--child-timeout", type=float, default=120.0)
args = parser.parse_args()

simple.LoadPlugin(args.plugin)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import faceplan_pipeline as pipeline  # noqa: E402

TOLERANCE, MIN_PRECOMPUTE_S, EDIT_PERIOD_S = 1e-12, 2.0, 0.010
failures = []


def check(cond, what):
    print(("ok:   " if cond else "FAIL: ") + what, flush=True)
    if not cond:
        failures.append(what)


def quiet(proxies):
    for p in proxies:
        p.GetClientSideObject().AddObserver("WarningEvent", lambda o, e: None)


def cut_curves(k):
    u = list(pipeline.CURVE_U)
    u[5] += 0.4 * math.sin(0.9 * k)
    u[8] += 0.4 * math.cos(0.9 * k)
    return u, list(pipeline.CURVE_V)


def build():
    proxies = pipeline.build(args.data)
    proxies[4].ElementOrder = args.element_order
    quiet(proxies[2:])
    return proxies


class Actor:
    """Calls act(elapsed) from the filter's progress events once a precompute is under way."""

    def __init__(self, fem, act):
        self.fem, self.act, self.t0, self.last = fem, act, None, None
        fem.GetClientSideObject().AddObserver("ProgressEvent", self.on_progress)

    def on_progress(self, obj, event):
        p = obj.GetProgress()
        if p <= 0.1 or p >= 0.9:  # 0.1 .. 0.9 is the precompute's (or solve's) range
            return
        now = time.perf_counter()
        if self.t0 is None:
            self.t0 = now
        self.last = now
        self.act(now - self.t0)


if args.child:
    tissue, mandible, roi, cut, fem = build()
    start = [None]

    def act(elapsed):
        if elapsed >= 0.2 and start[0] is None:
            start[0] = elapsed
            print("child: %s at %.2f s into the precompute" % (args.child, elapsed), flush=True)
            if args.child == "exit":
                sys.exit(0)  # raised in a VTK callback: Python exits the process from here
            simple.Delete(fem)

    actor = Actor(fem, act)
    fem.UpdatePipeline()
    print("child: the update returned", flush=True)
    if args.child == "delete":
        # The session goes on: a new filter on the same inputs works.
        fem2 = simple.CondensedFEMDeform(Input=tissue, Bone=cut)
        fem2.ContactDistance = 1.0
        fem2.UpdatePipeline()
        ok = servermanager.Fetch(fem2).GetNumberOfPoints() > 0
        print("child: a new filter after the delete %s" % ("works" if ok else "FAILED"), flush=True)
        sys.exit(0 if ok else 1)
    sys.exit(0)

# 1. Rapid edits during a precompute, then an ROI change in the middle of it.
tissue, mandible, roi, cut, fem = build()
state = {"edits": 0, "roi_changed_at": None}
FINAL_RADIUS = 20.0


def edit(elapsed):
    # The edits whose 10 ms slots have passed, at most 8 per callback (callbacks come every 20 ms;
    # an unbounded backlog would keep the callback from returning).
    due = min(int(elapsed / EDIT_PERIOD_S), state["edits"] + 8)
    while state["edits"] < due:
        state["edits"] += 1
        cut.CurveU, cut.CurveV = cut_curves(state["edits"])
    if state["roi_changed_at"] is None and elapsed >= 1.0:
        state["roi_changed_at"] = elapsed
        roi.Region.Radius = FINAL_RADIUS


actor = Actor(fem, edit)
t0 = time.perf_counter()
fem.UpdatePipeline()
first_update_s = time.perf_counter() - t0
precompute_s = (actor.last - actor.t0) if actor.t0 else 0.0
def precompute_count():
    fem.UpdatePropertyInformation()
    return fem.GetPropertyValue("PrecomputeCount")


print("first update %.2f s (precompute window %.2f s), %d edits applied, ROI changed at %s s"
      % (first_update_s, precompute_s, state["edits"], state["roi_changed_at"]))
check(precompute_s >= MIN_PRECOMPUTE_S, "the precompute lasted >= %.0f s (%.2f s)" % (MIN_PRECOMPUTE_S, precompute_s))
check(state["edits"] >= 0.9 * precompute_s / EDIT_PERIOD_S,
      "an edit every 10 ms during it (%d edits in %.2f s)" % (state["edits"], precompute_s))
check(state["roi_changed_at"] is not None, "the ROI changed during the precompute")
actor.act = lambda elapsed: None
fem.UpdatePipeline()  # what the next render does: the edits made the pipeline out of date
count = precompute_count()
# The first precompute and one for the ROI change; the cut edits reuse them.
check(count == 2, "two precomputes in all: the first and the ROI change's (%d)" % count)
u = vtk_to_numpy(servermanager.Fetch(fem).GetPointData().GetArray("Displacement")).copy()
f_tissue, f_mandible, f_roi, f_cut, f_fem = build()
f_roi.Region.Radius = FINAL_RADIUS
f_cut.CurveU, f_cut.CurveV = cut_curves(state["edits"])
f_fem.UpdatePipeline()
ref = vtk_to_numpy(servermanager.Fetch(f_fem).GetPointData().GetArray("Displacement")).copy()
diff = float(np.abs(u - ref).max() / np.abs(ref).max()) if u.shape == ref.shape else math.inf
check(diff <= TOLERANCE, "the final output belongs to the final inputs (relative difference %.3g to a fresh "
      "pipeline)" % diff)
for p in (f_fem, f_cut, f_roi, f_mandible, f_tissue):
    simple.Delete(p)

# 2 and 3. The filter deleted, and pvpython exiting, while a precompute runs (child processes).
pvpython = os.environ.get("PVPYTHON", "pvpython")
for child in ("delete", "exit"):
    cmd = [pvpython, "--force-offscreen-rendering", os.path.abspath(__file__), "--plugin", args.plugin,
           "--data", args.data, "--element-order", "0", "--child", child]
    t0 = time.perf_counter()
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=args.child_timeout)
        took = time.perf_counter() - t0
        lines = [l for l in (r.stdout + r.stderr).splitlines() if l.startswith("child:")]
        print("\n".join(lines))
        check(r.returncode == 0 and any("at " in l for l in lines),
              "%s during a precompute: the process ended with status %d in %.1f s" % (child, r.returncode, took))
    except subprocess.TimeoutExpired:
        check(False, "%s during a precompute: no end within %.0f s (deadlock)" % (child, args.child_timeout))

print("soak race: %s" % ("PASS" if not failures else "FAIL (%d)" % len(failures)))
sys.exit(1 if failures else 0)
