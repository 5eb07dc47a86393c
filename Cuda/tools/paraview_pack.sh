# SPDX-License-Identifier: BSD-3-Clause
# Sourced by the Cuda/tools scripts that bring Debian's ParaView to a GPU host that has none
# (gpu_pipeline_latency.sh: pvpython; gpu_gui_drag.sh: the paraview GUI under Xvfb). A pack is the set
# of files one run opened on a machine with ParaView (found with strace), less the C runtime every
# host has and the GPU driver the host brings, in Debian's layout under a root folder, as a .tar.xz;
# a pack larger than what one transfer carries travels as parts <pack>.part-aa, -ab, ...
# Sourced before the caller changes to the repository root: PACK and PLUGIN_DIR are made absolute.

[ -n "${PACK:-}" ] && PACK=$(realpath "$PACK")
[ -n "${PLUGIN_DIR:-}" ] && PLUGIN_DIR=$(realpath "$PLUGIN_DIR")
[ -n "${BASELINE_PLUGIN_DIR:-}" ] && BASELINE_PLUGIN_DIR=$(realpath "$BASELINE_PLUGIN_DIR")
ROOT=/tmp/pvroot # where a pack is unpacked

# pack_find_plugin HOW: prints the FacePlan plugin under $FACEPLAN_BUILD_DIR (default build), or
# says to build it HOW first and fails.
pack_find_plugin() {
  local build=${FACEPLAN_BUILD_DIR:-build} plugin
  plugin=$(find "$build" -name FacePlan.so -path '*paraview*plugins*' | head -n 1)
  [ -n "$plugin" ] || { echo "no FacePlan.so under $build: build $1 first" >&2; return 1; }
  echo "$plugin"
}

# pack_stage TRACE STAGE: copies every file the run traced in TRACE (strace -f -e
# trace=openat,open,execve,... -o TRACE) opened into STAGE, under the path Debian keeps it at.
pack_stage() {
  local trace=$1 stage=$2 f src dest
  rm -rf "$stage" && mkdir -p "$stage/usr/lib/x86_64-linux-gnu" "$stage/usr/bin"
  # realpath -s: /usr/bin/../lib/x.so (a RUNPATH) becomes /usr/lib/x.so, the name the loader asked
  # for (a link's name, not its target's) kept.
  grep -v ENOENT "$trace" | grep -oE '"/[^"]+"' | tr -d '"' | xargs realpath -s 2>/dev/null | sort -u |
    grep -E '^/(usr|lib|lib64|bin|sbin)/' | grep -vE '^/usr/local/' |
    grep -vE '/(libc|libm|libpthread|libdl|librt|libresolv|libstdc\+\+|libgcc_s)\.so|/ld-linux|/libnss_|nvidia|/libcuda\.|-nspkg\.pth$' |
    while read -r f; do
      [ -f "$f" ] || continue
      # /lib, /bin are /usr/lib, /usr/bin on Debian (merged /usr): one layout, the one a RUNPATH or a
      # relative search (VTK finds its Python packages from its libraries) expects.
      dest=${f#/usr/} && dest=$stage/usr/${dest#/}
      mkdir -p "$(dirname "$dest")"
      case "$f" in
        */__pycache__/*.pyc) # Python uses a cached module only beside its source, same mtime
          src="$(dirname "$(dirname "$f")")/$(basename "$f" | sed 's/\.cpython-[0-9]*\.pyc$//').py"
          cp -L --preserve=timestamps "$f" "$dest"
          [ -f "$src" ] && cp -L --preserve=timestamps "$src" "$(dirname "$(dirname "$dest")")/" ;;
        *) cp -L --preserve=timestamps "$f" "$dest" ;;
      esac
    done
}

# pack_write STAGE PACK [PART_SIZE]: STAGE as PACK (.tar.xz); with PART_SIZE (e.g. 50M) also as
# parts PACK.part-aa, -ab, ... of at most that size, the whole pack then removed.
pack_write() {
  local stage=$1 pack=$2 part=${3:-}
  mkdir -p "$(dirname "$pack")"
  rm -f "$pack" "$pack".part-*
  tar -C "$stage" -cf - . | xz -T2 -9 >"$pack" || return 1
  if [ -n "$part" ]; then
    split -b "$part" "$pack" "$pack.part-" && rm -f "$pack"
  fi
  ls -l "$pack"*
}

# pack_unpack PACK ROOT: unpacks PACK, or its parts PACK.part-* in order, into a fresh ROOT.
pack_unpack() {
  local pack=$1 root=$2
  rm -rf "$root" && mkdir -p "$root"
  if [ -f "$pack" ]; then
    xz -dc "$pack" | tar -xf - -C "$root"
  else
    compgen -G "$pack.part-*" >/dev/null || { echo "no pack $pack nor its parts"; return 1; }
    cat "$pack".part-* | xz -dc | tar -xf - -C "$root"
  fi || { echo "the pack $pack is incomplete"; return 1; }
}

# pack_variants ROUND: the builds to run in round ROUND, in order: "main" alone, or with
# BASELINE_PLUGIN_DIR set "main baseline" and "baseline main" by turns, so that neither build
# always runs second. Each run puts its own plugin folder first on LD_LIBRARY_PATH: both builds
# name their library libFacePlanFilters.so.
pack_variants() {
  if [ -z "${BASELINE_PLUGIN_DIR:-}" ]; then
    echo main
  elif [ $(($1 % 2)) = 0 ]; then
    echo "baseline main"
  else
    echo "main baseline"
  fi
}

# pack_environment ROOT PLUGIN_DIR: the environment that runs the pack's programs from ROOT: its
# libraries first, then the plugin's and the host's GPU driver and CUDA.
pack_environment() {
  local root=$1 plugin_dir=$2
  export LD_LIBRARY_PATH=$root/usr/lib/x86_64-linux-gnu:$root/usr/lib:$plugin_dir:/usr/local/nvidia/lib64:/usr/local/nvidia/lib:/usr/local/cuda/lib64:/usr/local/cuda/lib:${LD_LIBRARY_PATH:-}
  export PYTHONHOME=$root/usr
}
