#!/bin/sh
# The large-scan targets (docs/LARGE_SCANS.md): a 100M-point LAZ to LAZ with qs and jet R2 in at most
# 6 minutes and 4 GB over all processes; a 100M-vertex PLY mesh, mru R2, PLY out, in at most 10 minutes
# and 6 GB; a 1M-point window equal to the in-memory call; the same output from two workers started by
# hand on 127.0.0.1. They need the whole machine (about 25 GB of disk in DATA): run them on a quiet one.
#
#   sh benchmarks/bench_tiles_scale.sh [DATA folder, default /tmp/curvlab-scale] [points, default 100000000]
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DATA=${1:-/tmp/curvlab-scale}
N=${2:-100000000}
PY=${PYTHON:-python}
export PYTHONPATH="$ROOT"
mkdir -p "$DATA"
cd "$ROOT"

[ -f "$DATA/terrain$N.laz" ] || $PY benchmarks/make_terrain_laz.py "$N" "$DATA/terrain$N.laz"
[ -f "$DATA/mesh$N.ply" ] || $PY benchmarks/make_mesh_ply.py "$N" "$DATA/mesh$N.ply"

# each command's wall time, CPU time and peak memory summed over every process it starts
run() { $PY -c "import sys; sys.path.insert(0, 'benchmarks'); from bench_tiles import measure; \
m = measure(sys.argv[1:]); print(f\"wall {m['wall']:.0f} s, cpu {m['cpu']:.0f} s, peak {m['peak'] / 2**30:.2f} GiB resident, {m['own'] / 2**30:.2f} GiB own (all processes), exit {m['rc']}\"); \
print(m['out'][-2000:])" "$@"; }

for M in qs jet; do
  echo "== $N points LAZ -> LAZ, $M R2, --memory 4GB"
  run $PY -m curv.cli estimate "$DATA/terrain$N.laz" -m $M -r 2 -o "$DATA/out-$M.laz" --memory 4GB --quiet
  echo "== the interior of a 1M-point window against the in-memory call"
  $PY benchmarks/check_window.py "$DATA/terrain$N.laz" "$DATA/out-$M.laz" -m $M -r 2 --points 1000000
done

echo "== $N-vertex mesh, mru R2, PLY out, --memory 6GB"
run $PY -m curv.cli estimate "$DATA/mesh$N.ply" -m mru -r 2 -o "$DATA/out-mesh.ply" --memory 6GB --quiet

echo "== two workers started by hand on 127.0.0.1 against the plain run (10M points)"
[ -f "$DATA/terrain10000000.laz" ] || $PY benchmarks/make_terrain_laz.py 10000000 "$DATA/terrain10000000.laz"
dask scheduler --host 127.0.0.1 --port 8786 --no-dashboard > "$DATA/scheduler.log" 2>&1 &
S=$!
sleep 3
CURV_THREADS=1 dask worker tcp://127.0.0.1:8786 --nthreads 1 --memory-limit 2GB --no-dashboard > "$DATA/w1.log" 2>&1 &
W1=$!
CURV_THREADS=1 dask worker tcp://127.0.0.1:8786 --nthreads 1 --memory-limit 2GB --no-dashboard > "$DATA/w2.log" 2>&1 &
W2=$!
sleep 5
# the same tiles in both runs (--tile-size): the same arithmetic, so the same bits
run $PY -m curv.cli estimate "$DATA/terrain10000000.laz" -m qs -o "$DATA/cluster.laz" --scheduler tcp://127.0.0.1:8786 --tile-size 1000000 --quiet
kill $W1 $W2 $S
run $PY -m curv.cli estimate "$DATA/terrain10000000.laz" -m qs -o "$DATA/plain.laz" --tile-size 1000000 --memory 4GB --quiet
$PY -c "import laspy, numpy as np, sys; a, b = laspy.read(sys.argv[1]), laspy.read(sys.argv[2]); \
print('cluster output == plain output:', all(np.array_equal(a[d], b[d], equal_nan=True) for d in a.point_format.dimension_names))" \
  "$DATA/cluster.laz" "$DATA/plain.laz"
