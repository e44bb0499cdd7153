#!/usr/bin/env bash
# deploy/slurm on a real Slurm: munged, slurmctld and slurmd started on this machine
# (deploy/slurm/local-cluster.sh), the real gonogo-server under srun --mpi=pmix, the real CLI.
#
#   slurm_test.sh SOURCE_DIR BUILD_DIR
#
# 1. The service script: SERVING through the endpoint file; a second server on the same data
#    directory is refused; a map is scancel'ed mid-job (the server drains, the job goes back to
#    QUEUED); a second submission resumes it and it finishes with the first run's curves reused.
# 2. The batch script: one map from a request file; USR1 (the time-limit warning) mid-job drains
#    and requeues it, and the requeued run finishes the same job with the curves already made; the
#    products are there and open in GDAL. A request naming a missing file exits 2.
set -euo pipefail
source_dir=$(cd "${1:?usage: slurm_test.sh SOURCE_DIR BUILD_DIR}" && pwd)
build_dir=$(cd "${2:?usage: slurm_test.sh SOURCE_DIR BUILD_DIR}" && pwd)
if [ "$(id -u)" -ne 0 ]; then echo "slurm_test: needs root to start the Slurm daemons"; exit 77; fi

work=$(mktemp -d /tmp/gonogo-slurm-test.XXXXXX)
chmod 0755 "$work"  # munged runs as user munge and needs its way to its socket
cluster=$work/cluster
cleanup() {
  scancel --user root 2>/dev/null || true
  "$source_dir/deploy/slurm/local-cluster.sh" stop "$cluster" || true
  [ "${KEEP_WORK:-0}" = 1 ] || rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*" >&2
  for f in "$work"/submit/*.log "$cluster"/log/slurmctld.log; do [ -f "$f" ] && { echo "--- $f"; tail -40 "$f"; }; done >&2
  exit 1
}
cluster_env=$("$source_dir/deploy/slurm/local-cluster.sh" start "$cluster") || fail "the Slurm daemons did not start"
eval "$cluster_env"
export SLURM_CONF
echo "slurm_test: cluster up ($(sinfo -h -N -o '%N %c CPUs %T'))"

submit=$work/submit
mkdir -p "$submit"
cd "$submit"
/usr/bin/python3 "$source_dir/clients/sample-data/make_sample_terrain.py" --out terrain --size 60 >/dev/null
export GONOGO_HOME=$source_dir GONOGO_BUILD_DIR=$build_dir GONOGO_DATA_DIR=$work/data
# The service listens on the node's name by default; where that name does not resolve, on loopback.
getent hosts "$(hostname)" > /dev/null || export GONOGO_LISTEN=127.0.0.1:0
gonogo=("$build_dir/clients/gonogo" --server @gonogo-endpoint)
map_args=(--cone-index terrain/cone_index.tif --elevation terrain/elevation.tif
          --soil-class terrain/soil_class.tif --soil-table terrain/soil_table.json
          --vehicle "$source_dir/clients/vehicles/fed_alpha.json" --tier empirical)
sql() { sqlite3 "$GONOGO_DATA_DIR/gonogo.sqlite" "$1"; }
wait_until() {  # wait_until SECONDS WHAT COMMAND...: polls COMMAND every 0.5 s
  local seconds=$1 what=$2; shift 2
  for _ in $(seq 1 $((seconds * 2))); do "$@" && return 0; sleep 0.5; done
  fail "$what not within $seconds s"
}
no_jobs() { [ -z "$(squeue -h -o %i)" ]; }
curves_stored() { sql "SELECT COUNT(*) FROM curves"; }
at_least_stored() { [ "$(curves_stored)" -ge "$1" ] 2>/dev/null; }
state_of() { sql "SELECT state FROM jobs WHERE id='$1'"; }

# --- 1. the service: scancel mid-job, resubmit, resume ------------------------------------------
service=$(sbatch --parsable --export=ALL,GONOGO_SERVER_ARGS="--task-delay-ms 150" \
  "$source_dir/deploy/slurm/gonogo-service.sbatch")
wait_until 120 "the endpoint file" test -s gonogo-endpoint
[ "$(stat -c %a gonogo-endpoint)" = 600 ] || fail "the endpoint file is not private: $(stat -c %a gonogo-endpoint)"
[ "$(wc -l < gonogo-endpoint)" = 2 ] || fail "the endpoint file should hold HOST:PORT and a token"
"${gonogo[@]}" health --wait 120 | grep -qx SERVING || fail "health is not SERVING"
if "$build_dir/server/gonogo-server" --data-dir "$GONOGO_DATA_DIR" --listen 127.0.0.1:0 > second.out 2>&1; then
  fail "a second server on the same data directory started"
fi
grep -q "is in use by another gonogo-server" second.out || fail "the second server's refusal: $(cat second.out)"

job=$("${gonogo[@]}" map --no-wait --out out-service "${map_args[@]}")
wait_until 120 "20 curves of $job" at_least_stored 20
scancel "$service"
wait_until 60 "the service's end after scancel" no_jobs
grep -q "job $job interrupted by the shutdown; queued for the next start" "gonogo-service-$service.log" ||
  fail "the scancel did not drain the server"
[ ! -e gonogo-endpoint ] || fail "the endpoint file outlived the service"
[ "$(state_of "$job")" = 1 ] || fail "job $job is not QUEUED after the scancel (state $(state_of "$job"))"
stored=$(sql "SELECT COUNT(*) FROM curves")
[ "$stored" -ge 20 ] || fail "$stored curves stored after the scancel"
echo "slurm_test: scancel after $stored curves; job $job QUEUED"

service=$(sbatch --parsable "$source_dir/deploy/slurm/gonogo-service.sbatch")
wait_until 120 "the second endpoint file" test -s gonogo-endpoint
"${gonogo[@]}" health --wait 120 > /dev/null || fail "the second service is not SERVING"
"${gonogo[@]}" watch "$job" > watch.out 2>/dev/null || fail "job $job did not finish: $(cat watch.out)"
hits=$(sql "SELECT cache_hits FROM jobs WHERE id='$job'")
total=$(sql "SELECT tasks_total FROM jobs WHERE id='$job'")
[ "$stored" -lt "$total" ] || fail "the scancel came after the last curve ($stored of $total): nothing was left to resume"
[ "$hits" -ge "$stored" ] || fail "the resumed job took $hits curves from the cache, fewer than the $stored stored"
"${gonogo[@]}" download "$job" --out out-service > /dev/null || fail "download of $job"
echo "slurm_test: resumed job $job DONE with $hits of $total curves from the first run"
scancel "$service"
wait_until 60 "the second service's end" no_jobs

# --- 2. the batch map: USR1 mid-job requeues, the requeued run finishes the same job -------------
mkdir -p request
cat > request/map.args <<ARGS
# gonogo map options, one per line; relative paths are this file's
--tier empirical
--name batch map
--cone-index ../terrain/cone_index.tif
--elevation ../terrain/elevation.tif   # m

--soil-class ../terrain/soil_class.tif
--soil-table ../terrain/soil_table.json
--vehicle $source_dir/clients/vehicles/fed_alpha.json
--design-slip 0.25
ARGS
rm -rf "$GONOGO_DATA_DIR"  # a fresh cache: the requeued run must have curves left to compute
batch=$(sbatch --parsable --export=ALL,GONOGO_SERVER_ARGS="--task-delay-ms 150" \
  "$source_dir/deploy/slurm/gonogo-map.sbatch" request/map.args out-batch)
wait_until 120 "the batch map's job id" test -s out-batch/.gonogo-job
batch_job=$(cat out-batch/.gonogo-job)
wait_until 120 "20 curves of the batch map" at_least_stored 20
scancel --batch --signal=USR1 "$batch"
wait_until 60 "the batch job's requeue" bash -c "squeue -h -j $batch -o %T | grep -q PENDING"
grep -q "draining, then requeueing" "gonogo-map-$batch.log" || fail "USR1 did not drain the batch map"
before=$(sql "SELECT COUNT(*) FROM curves")
# Slurm holds a requeued job for the credential lifetime (20 s on the test cluster) first.
wait_until 300 "the requeued batch map's end" no_jobs
grep -q "following job $batch_job of an earlier run" "gonogo-map-$batch.log" || fail "the requeued run did not follow job $batch_job"
grep -q "gonogo-map: ended with status 0" "gonogo-map-$batch.log" || fail "the requeued batch map did not end with status 0"
[ "$(state_of "$batch_job")" = 3 ] || fail "batch job $batch_job is not DONE"
[ "$(sql "SELECT COUNT(*) FROM jobs")" = 1 ] || fail "the requeued run made a second job"
batch_hits=$(sql "SELECT cache_hits FROM jobs WHERE id='$batch_job'")
[ "$batch_hits" -ge "$before" ] || fail "the requeued map took $batch_hits curves from the cache, fewer than the $before made before USR1"
for f in summary.json; do [ -s "out-batch/$f" ] || fail "no out-batch/$f"; done
[ ! -e out-batch/.gonogo-job ] || fail "the finished batch map left its job file"
for tif in out-batch/*.tif; do
  gdalinfo "$tif" > /dev/null || fail "GDAL cannot open $tif"
done
ls out-batch/*.tif > /dev/null || fail "no GeoTIFF products in out-batch"
echo "slurm_test: batch map DONE after a requeue, $batch_hits curves from before it; $(ls out-batch | wc -l) products"

# A request naming a missing raster: exit status 2, nothing submitted.
sed 's|../terrain/cone_index.tif|../terrain/missing.tif|' request/map.args > request/bad.args
set +e
sbatch --wait --quiet "$source_dir/deploy/slurm/gonogo-map.sbatch" request/bad.args out-bad
bad_status=$?
set -e
[ "$bad_status" = 2 ] || fail "a request naming a missing raster exited $bad_status, not 2"
echo "slurm_test: a bad request exits 2"
echo "slurm_test: PASS"
