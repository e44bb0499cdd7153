#!/usr/bin/env bash
# The main job on a fresh machine: installs the dependencies, builds, makes the bundled sample terrain,
# starts gonogo-server on the embedded default (one process, data under ./gonogo-data), maps the
# sample with the FED Alpha vehicle through the gonogo CLI, and leaves the products in ./out/sample.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${GONOGO_BUILD_DIR:-$root/build}
data=${GONOGO_DATA_DIR:-$root/gonogo-data}
out=${GONOGO_OUT_DIR:-$root/out/sample}
terrain=$root/out/sample-terrain

"$root/deploy/install-deps.sh"
"$root/deploy/build.sh"

/usr/bin/python3 "$root/clients/sample-data/make_sample_terrain.py" --out "$terrain" --size 200

endpoint_file=$(mktemp)
"$root/deploy/gonogo-supervise" -- "$build/server/gonogo-server" --data-dir "$data" --listen 127.0.0.1:0 \
  --endpoint-file "$endpoint_file" > "$root/out/gonogo-server.log" 2>&1 &
server_pid=$!
trap 'kill -TERM $server_pid 2>/dev/null; wait $server_pid 2>/dev/null; rm -f "$endpoint_file"' EXIT
for _ in $(seq 1 100); do [ -s "$endpoint_file" ] && break; sleep 0.1; done
[ -s "$endpoint_file" ] || { echo "gonogo-server did not start:"; cat "$root/out/gonogo-server.log"; exit 1; }
echo "gonogo-server at $(cat "$endpoint_file") (log: out/gonogo-server.log)"

"$build/clients/gonogo" --server "@$endpoint_file" map \
  --cone-index "$terrain/cone_index.tif" --elevation "$terrain/elevation.tif" \
  --soil-class "$terrain/soil_class.tif" --soil-table "$terrain/soil_table.json" \
  --vehicle "$root/clients/vehicles/fed_alpha.json" --tier empirical --out "$out" \
  --name "sample terrain"

echo
echo "Products in $out:"
ls -l "$out"
/usr/bin/python3 - "$out/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print("cells %d valid of %d, %.3f km2" % (s["cells"]["valid"], s["cells"]["total"], s["valid_area_km2"]))
for k in ("GO", "SLOW-GO", "NO-GO"):
    c = s["classes"][k]
    print("  %-8s %6.2f %%  %.4f km2" % (k, c["percent_of_valid"], c["area_km2"]))
print("mean speed %.1f km/h (%.1f km/h where mobile)" % (s["mean_speed_kmh"], s["mean_speed_kmh_where_mobile"]))
t = s["tasks"]
print("traction tasks %d: %d computed, %d from the cache" % (t["total"], t["computed"], t["cache_hits"]))
PY
