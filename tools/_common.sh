# Shared by tools/book.sh and tools/test.sh (sourced, not run): repository root as working
# directory, one BLAS thread, a fixed hash seed, the Python to use and a step banner.
cd "$(dirname "${BASH_SOURCE[0]}")/.."
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 PYTHONHASHSEED=0
export PYDEVD_DISABLE_FILE_VALIDATION=1
PYTHON="${PYTHON:-python}"
step() { printf '\n==> %s\n' "$*"; }
start=$(date +%s)
