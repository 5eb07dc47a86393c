#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Fails when a shipped library defines a symbol of the comparison paths or of the test and benchmark
# support (FacePlanComparison, FacePlanTestSupport: mesh generators, test scenes, the CalculiX
# runner, the .vtu reader, the boundary-node sets): the plugin must not carry them.
# Usage: check_shipped_symbols.sh <library>...
set -euo pipefail
pattern='FreeSystem|ConjugateGradient|SinglePrecisionCholesky|ReverseCuthillMcKee|TraditionalBand|MassSpring|FloatCpu|ShellMesh|AnalyticHollowSphere|ShellRequest|BoxTetMesh|faceplan::testing::|faceplan::testmesh::|faceplan::bench::|RunCalculix|ReadVtuTets'
status=0
for library in "$@"; do
  [ -f "$library" ] || { echo "missing: $library"; exit 1; }
  found=$(nm -C --defined-only "$library" 2>/dev/null | grep -E "$pattern" || true)
  if [ -n "$found" ]; then
    echo "$library defines comparison or test-support symbols:"
    echo "$found" | head -20
    status=1
  else
    echo "$library: $(nm -C --defined-only "$library" | wc -l) symbols, none from comparison or test support"
  fi
done
exit $status
