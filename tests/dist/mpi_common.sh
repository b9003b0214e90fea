# Sourced by the MPI test scripts after they set `name`, `cli`, `mpiexec` and `work`: exits 77 (skipped) when there
# is no mpirun, sets `launch` (mpirun with --oversubscribe, and --allow-run-as-root for root, which Open MPI
# refuses otherwise), empties the work folder and writes the small synthetic set both tests train on to
# "$work/data" (seed 3, one take).
if [[ -z "$mpiexec" || ! -x "$(command -v "$mpiexec" || true)" ]]; then
  echo "$name: no mpirun found (./setup.sh --mpi installs openmpi-bin): skipped"
  exit 77
fi
launch=("$mpiexec" --oversubscribe)
if [[ $(id -u) -eq 0 ]]; then launch+=(--allow-run-as-root); fi
rm -rf "$work"
mkdir -p "$work"
"$cli" synth --out "$work/data" --takes 1 --seed 3 >/dev/null
