#!/bin/sh
# Reproduce docs/mutation.md: the seeded sample with the baseline kill suite (core tests
# only), then its survivors again with the new tests/test_mutation_kills_*.py, then the
# tables.  One worker, niced; ~1 h on two shared cores.  Run from the repository root with
# the project's Python (cosmic-ray installed: pip install -e '.[mutation]').
set -e
cd "$(dirname "$0")/.."
PY=${PYTHON:-python}
nice -n 10 $PY -m mutation.run --sample 300 --sample-fast 180 --seed 20260511 \
    --baseline-suite --out mutation/out/baseline
rm -rf mutation/out/after && cp -r mutation/out/baseline mutation/out/after
nice -n 10 $PY -m mutation.run --out mutation/out/after --rerun-survivors
$PY -m mutation.run --out mutation/out/after --table mutation/out/baseline > mutation/out/table.md
echo "tables in mutation/out/table.md"
# every mutant of inertia.py with the final kill suite (~20 min): ALL_INERTIA=1 sh mutation/run.sh
if [ "${ALL_INERTIA:-0}" = 1 ]; then
    nice -n 10 $PY -m mutation.run --all --modules inertia --out mutation/out/all_inertia
fi
# gpme_core/kernels.py (issue 25): its own seeded sample of 160, numba on, every mutant
# recompiled (~80 min), before the kill file written for its survivors
# (tests/test_mutation_kills_kernels.py), then its survivors again with it (~15 min):
# KERNELS=1 sh mutation/run.sh
if [ "${KERNELS:-0}" = 1 ]; then
    nice -n 10 $PY -m mutation.run --modules kernels --sample 160 --seed 20260511 \
        --leave-out tests/test_mutation_kills_kernels.py --out mutation/out/kernels
    rm -rf mutation/out/kernels_after && cp -r mutation/out/kernels mutation/out/kernels_after
    nice -n 10 $PY -m mutation.run --out mutation/out/kernels_after --rerun-survivors
    $PY -m mutation.run --out mutation/out/kernels_after --table mutation/out/kernels \
        > mutation/out/table_kernels.md
    echo "kernels.py tables in mutation/out/table_kernels.md"
fi
