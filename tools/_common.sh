# Shared by tools/book.sh and tools/test.sh (sourced, not run): repository root as working
# directory, one BLAS thread, a fixed hash seed, plain logs, the Python to use and a step banner.
#
# The Python: the active virtual environment when there is one; otherwise .venv in the repository,
# created on first use with `python3 -m venv` (or `$PYTHON -m venv` when PYTHON is set) and reused
# afterwards. Every tool (pip, symrb, jupyter-book, pytest, ruff, mypy) then runs from it.
cd "$(dirname "${BASH_SOURCE[0]}")/.."
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 PYTHONHASHSEED=0
export PYDEVD_DISABLE_FILE_VALIDATION=1
# The book's own code (book/lib/symrb_book, not part of the wheel) is importable by the pages'
# kernels, which inherit this environment.
export PYTHONPATH="$PWD/book/lib${PYTHONPATH:+:$PYTHONPATH}"
# Notebook kernels start from tools/jupyter/kernels/python3, which only lowers the kernel's own
# log level (no "Kernel is running over TCP without encryption" once per page).
export JUPYTER_PATH="$PWD/tools/jupyter${JUPYTER_PATH:+:$JUPYTER_PATH}"
# No colour codes in logs that are not a terminal (tools/build_book.py strips Sphinx's).
if [ ! -t 1 ]; then export NO_COLOR=1; fi

# Seconds since the outermost script started (tools/test.sh passes its start to tools/book.sh).
export SYMRB_T0="${SYMRB_T0:-$(date +%s)}"
elapsed() { echo $(($(date +%s) - SYMRB_T0)); }
step() { printf '\n==> %s  [%s s]\n' "$*" "$(elapsed)"; }
die() {
    printf 'error: %s\n' "$*" >&2
    exit 2
}

# use_python: point PYTHON, VIRTUAL_ENV and PATH at the virtual environment every step runs in.
use_python() {
    if [ -n "${SYMRB_PYTHON_READY:-}" ]; then # tools/test.sh already did it
        echo "using $VIRTUAL_ENV, as set up by the calling script"
        return
    fi
    local base="${PYTHON:-python3}" prefix version
    command -v "$base" >/dev/null 2>&1 ||
        die "'$base' not found: install Python 3.11 or newer, or set PYTHON=/path/to/python3"
    if ! "$base" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
        version="$("$base" -c 'import platform; print(platform.python_version())' 2>&1 || true)"
        die "$base is Python $version; symrb needs 3.11 or newer (set PYTHON=/path/to/python3.11)"
    fi
    if "$base" -c 'import sys; sys.exit(sys.prefix == sys.base_prefix)'; then
        prefix="$("$base" -c 'import sys; print(sys.prefix)')"
        echo "using the active virtual environment $prefix"
    else
        prefix="$PWD/.venv"
        if .venv/bin/python -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
            echo "no virtual environment active: using .venv (delete it to start afresh)"
        else
            "$base" -c 'import ensurepip, venv' 2>/dev/null ||
                die "$base cannot create a virtual environment (no venv/ensurepip module);" \
                    "on Debian or Ubuntu: sudo apt install python3-venv"
            echo "no virtual environment active: creating .venv with $base -m venv" \
                "(reused on later runs)"
            rm -rf .venv
            "$base" -m venv .venv || die "$base -m venv .venv failed (see above)"
        fi
    fi
    PYTHON="$prefix/bin/python"
    [ -x "$PYTHON" ] || die "no $PYTHON in the virtual environment $prefix"
    export PYTHON VIRTUAL_ENV="$prefix" PATH="$prefix/bin:$PATH" SYMRB_PYTHON_READY=1
    unset PYTHONHOME
    hash -r
}

# install_symrb EXTRA: `pip install -e ".[EXTRA]"` into that environment. In .venv, a stamp keyed
# on pyproject.toml skips the install when nothing changed; in a venv of the user's own, pip runs
# every time (quietly). The test extra includes the book extra.
install_symrb() {
    local extra="$1" stamp="" key="" covering="$1" e
    case "$extra" in book) covering="book test all" ;; test) covering="test all" ;; esac
    for e in $covering; do # installed earlier in this run (tools/test.sh before tools/book.sh)
        if [ "${SYMRB_INSTALLED:-}" = "$e" ]; then
            echo "symrb[$e] was installed earlier in this run"
            return
        fi
    done
    if [ "$VIRTUAL_ENV" = "$PWD/.venv" ]; then
        stamp=".venv/symrb-install.stamp"
        key="$(sha256sum pyproject.toml | cut -d' ' -f1)"
        key="$key $("$PYTHON" -c 'import platform; print(platform.python_version())')"
        for e in $covering; do
            if [ "$(cat "$stamp" 2>/dev/null)" = "$e $key" ]; then
                echo "symrb[$e] is already installed in .venv (pyproject.toml unchanged since)"
                export SYMRB_INSTALLED="$e"
                return
            fi
        done
        rm -f "$stamp"
    fi
    echo "pip install -e '.[$extra]' into $VIRTUAL_ENV (minutes when it starts empty)"
    # -qq: pip's errors only, not warnings about the user's own pip configuration
    "$PYTHON" -m pip install -qq --disable-pip-version-check -e ".[$extra]"
    if [ -n "$stamp" ]; then printf '%s %s\n' "$extra" "$key" >"$stamp"; fi
    export SYMRB_INSTALLED="$extra"
}

# worktree_state: what `git status` and the diff of tracked files say, as one line (CI compares
# it before and after to prove that nothing rewrote a tracked file).
worktree_state() {
    {
        git status --porcelain=v1 --untracked-files=all
        git diff HEAD --binary
    } | sha256sum | cut -d' ' -f1
}
