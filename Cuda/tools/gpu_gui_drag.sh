#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# GUI.Drag (Testing/GUI/TestGUIDrag.py in the real `paraview` GUI) with GPU rendering: the GUI on an
# Xvfb display whose GLX clients draw through the NVIDIA driver (__GLX_VENDOR_LIBRARY_NAME=nvidia).
# Fails unless the render window reports an NVIDIA renderer (not llvmpipe or another Mesa one).
# A GPU host without ParaView or an X server runs Debian's paraview, Qt and Xvfb from a pack of the
# files a GUI.Drag run under xvfb-run opens (paraview_pack.sh), with the plugin beside:
#   Cuda/tools/gpu_gui_drag.sh pack [PART_SIZE]  -> out/gui-pack.tar.xz (or its parts), out/gui-plugin/
#   OUT=<dir> PACK=out/gui-pack.tar.xz PLUGIN_DIR=out/gui-plugin Cuda/tools/gpu_gui_drag.sh run [ROUNDS]
# PACK names the pack or, when that file is absent, the prefix of its parts (PART_SIZE 50M: parts that
# fit a transfer of 64 MiB, carried one by one to a host that keeps them between calls).
# On a host with ParaView, Xvfb and a FacePlan build with the plugin, `run` without PACK uses them.
# The figures go to $OUT/gui_drag_gpu.txt (and each round's result JSON and logs beside it).
# BASELINE_PLUGIN_DIR=<dir> (a build of another commit, from the same pack step) runs it beside
# PLUGIN_DIR in every round, the two in alternating order, on the same display: its figures and the
# per-round pairs follow the main ones (the machine's drift cancels in the pairs).
# FACEPLAN_GLX_VENDOR=mesa tries the same steps on a host without NVIDIA's GLX (and fails the check).
set -uo pipefail
. "$(dirname "$0")/paraview_pack.sh"
cd "$(dirname "$0")/../.."


pack() {
  local plugin stage=/tmp/gui-pack trace=/tmp/gui-pack.trace
  plugin=$(pack_find_plugin "with the plugin") || return 1
  # Every file this very run opens: Xvfb (and xkbcomp, Mesa's swrast for its GLX), paraview, Qt.
  strace -f -e trace=openat,open,execve -o "$trace" xvfb-run -a -s "-screen 0 1280x1024x24" \
    python3 Testing/GUI/run_gui_test.py --script TestGUIDrag.py --paraview "$(command -v paraview)" \
    --paraview-arg=--no-mpi --plugin "$plugin" --source-dir "$PWD" --work-dir /tmp/gui-pack-run \
    >/tmp/gui-pack-run.log 2>&1 || { cat /tmp/gui-pack-run.log; echo "the traced GUI run failed"; return 1; }
  pack_stage "$trace" "$stage"
  # xkbcomp opens the keymap files relative to its root folder: the strace paths miss them.
  mkdir -p "$stage/usr/share/X11" && cp -rL /usr/share/X11/xkb "$stage/usr/share/X11/"
  rm -rf out/gui-plugin && mkdir -p out/gui-plugin
  cp "$plugin" "$(dirname "$plugin")/libFacePlanFilters.so" out/gui-plugin/
  pack_write "$stage" out/gui-pack.tar.xz "${1:-}"
}

# The pack's Xvfb finds Mesa's swrast (its GLX) and xkbcomp only where Debian keeps them.
link_into_system() { # TARGET LINK: a link at LINK unless something is there already
  [ -e "$2" ] || { mkdir -p "$(dirname "$2")" && ln -s "$1" "$2" && echo "linked $2"; }
}

run() {
  local out=${OUT:-/tmp/faceplan-gui-drag} rounds=${1:-3} paraview plugin xvfb display=:87
  mkdir -p "$out"
  if [ -n "${PACK:-}" ]; then
    pack_unpack "$PACK" "$ROOT" || return 1
    local lib=$ROOT/usr/lib/x86_64-linux-gnu
    link_into_system "$lib/dri/swrast_dri.so" /usr/lib/x86_64-linux-gnu/dri/swrast_dri.so
    link_into_system "$ROOT/usr/bin/xkbcomp" /usr/bin/xkbcomp
    local glx_nvidia
    glx_nvidia=$(find /usr/local/nvidia /usr/lib /usr/lib64 /lib -name 'libGLX_nvidia.so.0' 2>/dev/null | head -n 1)
    echo "NVIDIA's GLX: ${glx_nvidia:-not found}"
    export LD_LIBRARY_PATH=${glx_nvidia:+$(dirname "$glx_nvidia"):}${LD_LIBRARY_PATH:-}
    pack_environment "$ROOT" "$PLUGIN_DIR"
    unset PYTHONHOME # only paraview's (the wrapper below): the host's python3 runs the test wrapper
    mkdir -p /tmp/fontconfig-cache
    cat >"$ROOT/fonts.conf" <<EOF
<?xml version="1.0"?><!DOCTYPE fontconfig SYSTEM "fonts.dtd">
<fontconfig><dir>$ROOT/usr/share/fonts</dir><cachedir>/tmp/fontconfig-cache</cachedir></fontconfig>
EOF
    export FONTCONFIG_FILE=$ROOT/fonts.conf XLOCALEDIR=$ROOT/usr/share/X11/locale
    export QT_PLUGIN_PATH=$lib/qt5/plugins
    xvfb=$ROOT/usr/bin/Xvfb plugin=$PLUGIN_DIR/FacePlan.so
    paraview=$ROOT/paraview
    printf '#!/bin/sh\nPYTHONHOME=%s/usr exec %s/usr/bin/paraview "$@"\n' "$ROOT" "$ROOT" >"$paraview"
    chmod +x "$paraview"
  else
    xvfb=$(command -v Xvfb) || { echo "no Xvfb: set PACK (see the header)"; return 1; }
    paraview=$(command -v paraview) || { echo "no paraview: set PACK (see the header)"; return 1; }
    plugin=$(pack_find_plugin "with the plugin") || return 1
  fi
  if [ -n "${PACK:-}" ] && ldd "$ROOT/usr/bin/paraview" "$ROOT/usr/bin/Xvfb" "$plugin" | grep "not found"; then
    echo "missing libraries"
    return 1
  fi
  local xkb=()
  [ -n "${PACK:-}" ] && xkb=(-xkbdir "$ROOT/usr/share/X11/xkb")
  "$xvfb" "$display" -screen 0 1280x1024x24 -nolisten tcp "${xkb[@]}" >"$out/xvfb.log" 2>&1 &
  local xvfb_pid=$!
  sleep 3
  kill -0 "$xvfb_pid" 2>/dev/null || { echo "Xvfb did not start:"; cat "$out/xvfb.log"; return 1; }
  { nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; nproc; uname -r; } >"$out/machine.txt" 2>&1
  cat "$out/machine.txt"
  local status=0 round variant dir
  for round in $(seq 1 "$rounds"); do
    for variant in $(pack_variants "$round"); do
      local tag=r$round dir=$(dirname "$plugin")
      [ "$variant" = baseline ] && tag=r${round}_baseline dir=$BASELINE_PLUGIN_DIR
      LD_LIBRARY_PATH=$dir:${LD_LIBRARY_PATH:-} DISPLAY=$display \
        __GLX_VENDOR_LIBRARY_NAME=${FACEPLAN_GLX_VENDOR:-nvidia} python3 Testing/GUI/run_gui_test.py \
        --script TestGUIDrag.py --paraview "$paraview" --paraview-arg=--no-mpi --plugin "$dir/FacePlan.so" \
        --source-dir "$PWD" --work-dir "/tmp/gui-drag-$tag" --timeout 240 >"$out/round_$tag.log" 2>&1 ||
        status=1
      grep -vE '^info:' "$out/round_$tag.log"
      cp "/tmp/gui-drag-$tag/faceplan_gui_result.json" "$out/result_$tag.json" 2>/dev/null
      cp "/tmp/gui-drag-$tag/paraview_gui.log" "$out/paraview_gui_$tag.log" 2>/dev/null
      [ $status = 0 ] || break 2
    done
  done
  kill "$xvfb_pid" 2>/dev/null
  [ $status = 0 ] || { echo "the GUI run failed: see $out"; return 1; }
  python3 - "$out" "$rounds" "${BASELINE_PLUGIN_DIR:-}" <<'EOF' | tee "$out/gui_drag_gpu.txt"
import json, statistics, sys
out, rounds, baseline = sys.argv[1], int(sys.argv[2]), sys.argv[3]
def load(suffix):
    return [json.load(open("%s/result_r%d%s.json" % (out, r, suffix)))["info"] for r in range(1, rounds + 1)]
def summary(infos):
    gl = infos[0]
    print("OpenGL: %s | %s | %s" % (gl["gl_vendor"], gl["gl_renderer"], gl["gl_version"]))
    print("view %s, %d rounds of 12 moves; per frame, median of each round's medians (ms, wall):" % (
        gl["view_size"], rounds))
    series = (("default_", "ParaView's defaults"), ("", "FXAA off (drag setting)"),
              ("small_view_", "FXAA off, quarter view"), ("large_deformation_", "FXAA off, NeoHookean"))
    for prefix, name in series:
        def med(key):
            values = [i.get(prefix + key) for i in infos]
            return None if None in values else statistics.median(values)
        phases = " | ".join("%s %s" % (p, "%.1f" % med(p + "_ms_median") if med(p + "_ms_median") is not None else "-")
                            for p in ("pipeline", "representations", "render", "paint"))
        frame = med("frame_ms_median")
        solve = med("solve_ms_median")  # Condensed FEM Deform's own solve within the pipeline phase
        print("%-26s frame %7.1f ms = %5.1f updates/s (rounds: %s) | %s | solve %s" % (
            name, frame, 1e3 / frame, ", ".join("%.1f" % i[prefix + "updates_per_s_median"] for i in infos),
            phases, "%.1f" % solve if solve is not None else "-"))
    for prefix, name in (("", "linear"), ("large_deformation_", "NeoHookean")):
        per_move = {}
        for i in infos:
            for group, ms in i.get(prefix + "thread_cpu_ms_per_move", {}).items():
                per_move.setdefault(group, []).append(ms)
        if per_move:
            print("CPU per move by thread, %s (median of the rounds, ms): %s" % (name, ", ".join(
                "%s %.1f" % (g, statistics.median(v)) for g, v in sorted(
                    per_move.items(), key=lambda kv: -statistics.median(kv[1])))))
    return gl
infos = load("")
gl = summary(infos)
if baseline:
    base = load("_baseline")
    print("\nBaseline (%s), the same rounds:" % baseline)
    summary(base)
    print("\nPer round, this build against the baseline (frame ms, solve ms):")
    for prefix, name in (("", "linear"), ("large_deformation_", "NeoHookean")):
        pairs = ["%.1f/%.1f vs %.1f/%.1f" % (i[prefix + "frame_ms_median"], i.get(prefix + "solve_ms_median", 0),
                                              b[prefix + "frame_ms_median"], b.get(prefix + "solve_ms_median", 0))
                 for i, b in zip(infos, base)]
        ratio = statistics.median(b[prefix + "frame_ms_median"] / i[prefix + "frame_ms_median"]
                                  for i, b in zip(infos, base))
        print("  %-10s %s; median frame ratio baseline/this %.3f" % (name, "; ".join(pairs), ratio))
renderer = (gl["gl_vendor"] or "") + " " + (gl["gl_renderer"] or "")
if "NVIDIA" not in renderer or any(s in renderer for s in ("llvmpipe", "Mesa", "softpipe", "swrast")):
    print("FAIL: the frames were not drawn by the NVIDIA GPU (%s)" % renderer)
    sys.exit(1)
EOF
}

case "${1:-}" in
  pack) pack "${2:-}" ;;
  run) shift; run "$@" ;;
  *) echo "usage: $0 pack [PART_SIZE] | run [ROUNDS]"; exit 2 ;;
esac
