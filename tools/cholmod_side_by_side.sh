#!/usr/bin/env bash
# faer's Cholesky (the library's DirectSolver) beside CHOLMOD on the
# library's own systems (issue 18): exports the whole system of the first
# step's third Picard iterate of the 2D dam break and the 3D water column
# at the given sizes as Matrix Market, then factors each with both, best
# of 3, on 1 thread and on 2.
#
#   bash tools/cholmod_side_by_side.sh [OUT_DIR]
#
# Needs CHOLMOD's headers and library (Debian: libsuitesparse-dev) and,
# for CHOLMOD's supernodal kernels to be fair, an optimised BLAS (Debian:
# libopenblas0-pthread; with the reference BLAS CHOLMOD factors 2-7x
# slower). CHOLMOD runs twice: its default ordering (AMD or METIS, the
# better) and AMD alone.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/cholmod_side_by_side}"
mkdir -p "$out"
gcc -O2 -o "$out/cholmod_factor" tools/cholmod_factor.c -I/usr/include/suitesparse -lcholmod
cargo build -q --release --example solver_scaling --example factor_mtx
for run in dam2d:40 dam2d:80 dam2d:160 column3d:10 column3d:14 column3d:18; do
  stem="$out/${run/:/_a}"
  if [ ! -f "$stem.mtx" ]; then
    ./target/release/examples/solver_scaling --one "$run:direct" --steps 1 --export "$stem" > /dev/null
  fi
  echo "== $run ($stem.mtx)"
  for threads in 1 2; do
    ./target/release/examples/factor_mtx "$stem.mtx" --rhs "${stem}_rhs.mtx" --threads "$threads"
    for method in default amd; do
      OPENBLAS_NUM_THREADS=$threads OMP_NUM_THREADS=$threads \
        "$out/cholmod_factor" "$stem.mtx" "${stem}_rhs.mtx" 3 "$method"
    done
  done
done
