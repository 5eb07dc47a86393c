#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Two faceplan_benchmark binaries (e.g. a base commit's and the working tree's) on one scene, runs
# alternated so that both see the same machine, each under the environment's OpenBLAS kernels and
# under OpenBLAS's own choice (OPENBLAS_CORETYPE unset). Medians over the rounds, per stage.
#   Benchmarks/precompute_side_by_side.sh BASE_BIN NEW_BIN OUT_DIR [ROUNDS] [faceplan_benchmark args]
set -euo pipefail
base=$1 new=$2 out=$3 rounds=${4:-3}
shift 4 || shift $#
args=("$@")
[ ${#args[@]} -gt 0 ] || args=(--subdivisions 18 --layers 5 --precompute-repeats 3 --edits 200 --reference-repeats 3)
mkdir -p "$out"
env_kernels=${OPENBLAS_CORETYPE:-}
for round in $(seq 1 "$rounds"); do
  for kernels in environment own; do
    for which in base new; do
      bin=$base; [ "$which" = new ] && bin=$new
      name="$out/${which}_${kernels}_r${round}"
      if [ "$kernels" = own ]; then
        env -u OPENBLAS_CORETYPE "$bin" "${args[@]}" --json "$name.json" > "$name.txt" 2>&1
      else
        "$bin" "${args[@]}" --json "$name.json" > "$name.txt" 2>&1
      fi
      echo "round $round $kernels $which: $(grep -m1 '^precompute' "$name.txt")"
    done
  done
done
/usr/bin/python3 - "$out" "$env_kernels" <<'PY'
import glob, json, os, re, statistics, sys
out, env_kernels = sys.argv[1], sys.argv[2]
def load(path):  # the benchmark writes inf/nan where a figure does not apply
    return json.loads(re.sub(r':\s*-?(inf|nan)', ': null', open(path).read()))
rows = []
for kernels in ("environment", "own"):
    for which in ("base", "new"):
        runs = [load(p) for p in sorted(glob.glob(os.path.join(out, f"{which}_{kernels}_r*.json")))]
        if not runs:
            continue
        stages = {k: statistics.median(r["precompute_stage_ms"][k] for r in runs)
                  for k in runs[0]["precompute_stage_ms"]}
        edit = statistics.median(r["edit_ms_median"] for r in runs)
        diff = max(r["max_rel_diff_reference"] or 0 for r in runs)
        txt = open(os.path.join(out, f"{which}_{kernels}_r1.txt")).read()
        m = re.search(r"BLAS kernels: (\S+)", txt)
        rows.append((kernels, which, m.group(1) if m else "?", stages, edit, diff,
                     max(r["peak_rss_condensed_mb"] for r in runs), len(runs)))
keys = ["Reordering", "ElementStiffness", "Assembly", "Separation", "Factorization", "Condensation", "Total"]
lines = [f"OPENBLAS_CORETYPE in the environment: {env_kernels or '(unset)'}",
         "| kernels | binary | BLAS | " + " | ".join(keys) + " | per edit ms | max rel. diff to reference | peak RSS MB | rounds |",
         "|" + "---|" * (len(keys) + 7)]
for kernels, which, blas, stages, edit, diff, rss, n in rows:
    lines.append(f"| {kernels} | {which} | {blas} | " + " | ".join(f"{stages.get(k, 0):.0f}" for k in keys) +
                 f" | {edit:.3f} | {diff:.1e} | {rss:.0f} | {n} |")
open(os.path.join(out, "summary.md"), "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
