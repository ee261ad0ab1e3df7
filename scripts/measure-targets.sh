#!/usr/bin/env bash
# Measures the figures named by the issues, single thread, 1920x1080, release build.
# Each figure is the minimum over RUNS runs (default 5) of the CLI's --stats-json value.
# Usage: scripts/measure-targets.sh [RUNS]     (needs ../shared/data/sponza.obj for Sponza)
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-5}
cargo build -q --release -p obscura-cli
BIN=target/release/obscura
SPONZA=${SPONZA:-../shared/data/sponza.obj}
ATRIUM=(--eye 0,-10,2 --target 0,10,4 --up 0,0,1 --fov 60)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# best over runs of a JSON field path (dot separated) of --stats-json: the minimum
# (times) or, with pick=max, the maximum (rates)
measure_with() { # pick name field -- args...
  local pick=$1 name=$2 field=$3; shift 4
  local best=""
  for _ in $(seq "$RUNS"); do
    # stderr shown only on failure (Sponza's one degenerate face warns on every run)
    "$BIN" render "$@" --size 1920x1080 --threads 1 --time-limit none --stats-json "$tmp/s.json" -o "$tmp/o.png" \
      >/dev/null 2>"$tmp/err" || { cat "$tmp/err" >&2; exit 1; }
    v=$(python3 -c "import json; d=json.load(open('$tmp/s.json')); f='$field'.split('.'); [d:=d[k] for k in f]; print(d)")
    best=$(python3 -c "b='$best'; v=float('$v'); print(v if b=='' else $pick(float(b), v))")
  done
  printf '%-58s %12.2f\n' "$name" "$best"
}
measure() { measure_with min "$@"; }
measure_max() { measure_with max "$@"; }

echo "figure (min of $RUNS runs; rates: max)                              value"
if [[ -f $SPONZA ]]; then
  measure "Sponza load_ms (target < 300)" load_ms -- "$SPONZA" "${ATRIUM[@]}"
  measure "Sponza z-buffer render_ms (target < 15; llvmpipe ~60)" render_ms -- "$SPONZA" "${ATRIUM[@]}"
  measure "Sponza scanline render_ms (target < 3x z-buffer)" render_ms -- "$SPONZA" "${ATRIUM[@]}" --algo scanline
  measure_max "Sponza raycast-bvh Mrays/s (target >= 3; Embree 4.4)" stats.mrays_per_s -- "$SPONZA" "${ATRIUM[@]}" --algo raycast-bvh
  measure "Sponza BVH build_ms (target < 150; Embree ~140)" stats.build_ms -- "$SPONZA" "${ATRIUM[@]}" --algo raycast-bvh
  measure "Sponza warnock render_ms (report)" render_ms -- "$SPONZA" "${ATRIUM[@]}" --algo warnock
  measure "Sponza depth-sort render_ms (report)" render_ms -- "$SPONZA" "${ATRIUM[@]}" --algo depth-sort
fi
measure "demo:sphere z-buffer render_ms (target < 60)" render_ms -- demo:sphere
measure_max "demo:sphere raycast-bvh Mrays/s (target >= 6; Embree 11.5)" stats.mrays_per_s -- demo:sphere --algo raycast-bvh
measure "demo:triangles z-buffer render_ms" render_ms -- demo:triangles
"$BIN" render demo:triangles --size 1920x1080 --threads 1 --stats-json "$tmp/t.json" -o "$tmp/o.png" >/dev/null
python3 - "$tmp/t.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
tested = d["stats"]["pixels_tested"]
print(f"{'demo:triangles per-pixel depth tests per second':<58} {tested / (d['algorithm_ms'] / 1e3):12.3e}")
print("  (occlusion culling skips hidden blocks untested; covered samples per second,")
print("   the issue's figure (> 3e8): cargo bench -p obscura --bench zbuffer -- triangles)")
PY
if command -v /usr/bin/time >/dev/null; then
  rss=$( { /usr/bin/time -v "$BIN" render demo:sphere --size 1920x1080 --threads 1 -o "$tmp/o.png" >/dev/null; } 2>&1 | awk '/Maximum resident/ {print $6}')
  printf '%-58s %12.1f\n' "demo:sphere peak RSS MB (target < 400)" "$(echo "$rss/1024" | bc -l)"
fi
