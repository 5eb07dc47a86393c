# SPDX-License-Identifier: BSD-3-Clause
"""CTest wrapper of FacePlan's GUI tests: starts the real `paraview` GUI on a test script
(TestGUIUndoRedo.py unless --script names another one in this folder),
waits for the result file the script writes, optionally grabs the X screen (the whole GUI: pipeline
browser, Bezier Cut properties panel, render view) into a PNG, closes the GUI and checks the result.

    python3 run_gui_test.py --paraview <exe> --plugin <FacePlan.so> --source-dir <repo>
                            --work-dir <dir> [--script <name>.py] [--screenshot <png>] [--timeout <s>]
                            [--paraview-arg <arg>]...

Run it with an X display (faceplan_with_display.sh). Exit 0: every check passed; 1: a check failed,
the script raised, or the GUI did not report in time; 77 (CTest SKIP): no display.
Only the Python standard library (and ctypes' libX11) is needed: no screenshot tools.
"""
import argparse
import ctypes
import ctypes.util
import json
import os
import signal
import struct
import subprocess
import sys
import time
import zlib

SKIP = 77


class XImage(ctypes.Structure):
    _fields_ = [("width", ctypes.c_int), ("height", ctypes.c_int), ("xoffset", ctypes.c_int),
                ("format", ctypes.c_int), ("data", ctypes.POINTER(ctypes.c_ubyte)),
                ("byte_order", ctypes.c_int), ("bitmap_unit", ctypes.c_int),
                ("bitmap_bit_order", ctypes.c_int), ("bitmap_pad", ctypes.c_int),
                ("depth", ctypes.c_int), ("bytes_per_line", ctypes.c_int),
                ("bits_per_pixel", ctypes.c_int), ("red_mask", ctypes.c_ulong),
                ("green_mask", ctypes.c_ulong), ("blue_mask", ctypes.c_ulong)]


def open_x():
    # find_library searches the system's library cache only; the soname also finds a libX11 on
    # LD_LIBRARY_PATH (a ParaView run from a folder of its own).
    try:
        x11 = ctypes.CDLL(ctypes.util.find_library("X11") or "libX11.so.6")
    except OSError:
        return None, None
    x11.XOpenDisplay.restype = ctypes.c_void_p
    x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
    dpy = x11.XOpenDisplay(None)
    return x11, dpy


def grab_screen(path):
    """The X root window (what the GUI shows) as an RGB PNG, cropped to what is not background."""
    x11, dpy = open_x()
    if not dpy:
        print("screenshot: cannot open the X display")
        return False
    x11.XDefaultRootWindow.restype = ctypes.c_ulong
    x11.XDefaultRootWindow.argtypes = [ctypes.c_void_p]
    x11.XGetImage.restype = ctypes.POINTER(XImage)
    x11.XGetImage.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_int, ctypes.c_int,
                              ctypes.c_uint, ctypes.c_uint, ctypes.c_ulong, ctypes.c_int]
    x11.XDisplayWidth.argtypes = x11.XDisplayHeight.argtypes = [ctypes.c_void_p, ctypes.c_int]
    w, h = x11.XDisplayWidth(dpy, 0), x11.XDisplayHeight(dpy, 0)
    img = x11.XGetImage(dpy, x11.XDefaultRootWindow(dpy), 0, 0, w, h, ctypes.c_ulong(-1).value, 2)
    if not img:
        print("screenshot: XGetImage failed")
        return False
    im = img.contents
    if im.bits_per_pixel != 32 or im.red_mask != 0xFF0000 or im.blue_mask != 0xFF:
        print("screenshot: unsupported visual (%d bpp)" % im.bits_per_pixel)
        return False
    raw = ctypes.string_at(im.data, im.bytes_per_line * h)
    stride = im.bytes_per_line
    rows = []
    for y in range(h):
        line = raw[y * stride: y * stride + 4 * w]
        rgb = bytearray(3 * w)
        rgb[0::3], rgb[1::3], rgb[2::3] = line[2::4], line[1::4], line[0::4]
        rows.append(bytes(rgb))
    # Crop the black root window around the GUI's window(s).
    blank = bytes(3 * w)
    used = [y for y in range(h) if rows[y] != blank]
    if not used:
        print("screenshot: the screen is empty")
        return False
    y0, y1 = used[0], used[-1] + 1
    x0, x1 = w, 0
    for y in range(y0, y1, 4):
        r = rows[y]
        nz = [i // 3 for i in range(0, 3 * w, 3) if r[i:i + 3] != b"\0\0\0"]
        if nz:
            x0, x1 = min(x0, nz[0]), max(x1, nz[-1] + 1)
    rows = [r[3 * x0: 3 * x1] for r in rows[y0:y1]]
    write_png(path, x1 - x0, y1 - y0, rows)
    print("screenshot: %s (%dx%d)" % (path, x1 - x0, y1 - y0))
    return True


def write_png(path, w, h, rows):
    def chunk(tag, data):
        body = tag + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    # PNG "Up" filter on every row: flat GUI areas compress to almost nothing.
    prev = bytes(len(rows[0]))
    raw = bytearray()
    for r in rows:
        raw.append(2)
        raw += bytes((a - b) & 0xFF for a, b in zip(r, prev))
        prev = r
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(bytes(raw), 9)))
        f.write(chunk(b"IEND", b""))


def stop(proc):
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--paraview", required=True)
    ap.add_argument("--plugin", required=True)
    ap.add_argument("--source-dir", required=True)
    ap.add_argument("--work-dir", required=True)
    ap.add_argument("--script", default="TestGUIUndoRedo.py")
    ap.add_argument("--screenshot")
    ap.add_argument("--timeout", type=float, default=150.0)
    ap.add_argument("--paraview-arg", action="append", default=[],
                    help="one more argument for paraview (e.g. --no-mpi), repeatable")
    a = ap.parse_args()

    x11, dpy = open_x()
    if not dpy:
        print("SKIPPED: no X display")
        return SKIP

    os.makedirs(a.work_dir, exist_ok=True)
    result_path = os.path.join(a.work_dir, "faceplan_gui_result.json")
    if os.path.exists(result_path):
        os.remove(result_path)
    env = dict(os.environ)
    env.update(FACEPLAN_GUI_PLUGIN=os.path.abspath(a.plugin),
               FACEPLAN_GUI_DATA=os.path.join(a.source_dir, "Data"),
               FACEPLAN_GUI_SCRIPTS=os.path.join(a.source_dir, "scripts"),
               FACEPLAN_GUI_TESTS=os.path.join(a.source_dir, "Testing", "GUI"),
               FACEPLAN_GUI_RESULT=result_path,
               # a fresh settings folder: the default layout (pipeline browser + properties
               # panel) whatever the user's own ParaView settings are
               HOME=a.work_dir, XDG_CONFIG_HOME=os.path.join(a.work_dir, "config"))
    script = os.path.join(a.source_dir, "Testing", "GUI", a.script)
    name = os.path.splitext(a.script)[0]
    log_path = os.path.join(a.work_dir, "paraview_gui.log")
    log = open(log_path, "w")
    proc = subprocess.Popen([a.paraview, "--dr", "-geometry", "1280x1024+0+0", "--script=" + script]
                            + a.paraview_arg, env=env,
                            stdout=log, stderr=subprocess.STDOUT)
    deadline = time.time() + a.timeout
    try:
        while not os.path.exists(result_path):
            if proc.poll() is not None:
                print("FAIL: the paraview GUI exited (code %s) before the script reported" % proc.returncode)
                break
            if time.time() > deadline:
                print("FAIL: no result from the GUI within %.0f s" % a.timeout)
                break
            time.sleep(0.25)
        if os.path.exists(result_path) and a.screenshot and proc.poll() is None:
            time.sleep(4.0)  # the script has returned: let the GUI's event loop paint everything
            grab_screen(a.screenshot)
    finally:
        stop(proc)
        log.close()

    def print_gui_log():  # what ParaView itself said: the first clue to a failure
        with open(log_path) as f:
            print("--- the GUI's output (last 4000 characters) ---\n" + f.read()[-4000:])

    if not os.path.exists(result_path):
        print_gui_log()
        return 1
    with open(result_path) as f:
        result = json.load(f)
    for c in result["checks"]:
        print("%s: %s" % ("FAIL" if c in result["failures"] else "ok  ", c))
    print("info:", json.dumps(result["info"]))
    if result["error"]:
        print("FAIL: the GUI script raised:\n" + result["error"])
        print_gui_log()
        return 1
    if result["failures"] or not result["checks"]:
        print("%s: %d check(s) failed" % (name, len(result["failures"])))
        print_gui_log()
        return 1
    print("%s: all %d checks passed" % (name, len(result["checks"])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
